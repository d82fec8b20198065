"""Reads the legacy binary VTK frames haptic-sim writes (POLYDATA points + point data), and the
ParaView `.vtk.series` index beside them. A file in another layout is a ValueError naming it."""
import json
import pathlib

import numpy as np


def read_vtk(path: pathlib.Path) -> dict:
    data = pathlib.Path(path).read_bytes()
    pos = 0

    def line() -> str:
        nonlocal pos
        end = data.index(b"\n", pos)
        text = data[pos:end].decode()
        pos = end + 1
        return text

    header = [line() for _ in range(4)]
    if not header[0].startswith("# vtk DataFile") or header[2] != "BINARY" or header[3] != "DATASET POLYDATA":
        raise ValueError(f"{path}: not a binary legacy VTK POLYDATA file (header {header!r})")
    out = {"title": header[1]}
    n = 0
    while pos < len(data):
        text = line().strip()
        if not text:
            continue
        words = text.split()
        if words[0] == "POINTS":
            n = int(words[1])
            out["points"] = np.frombuffer(data, ">f4", 3 * n, pos).reshape(n, 3)
            pos += 12 * n
        elif words[0] == "VERTICES":
            pos += 4 * int(words[2])
        elif words[0] == "POINT_DATA":
            pass
        elif words[0] == "VECTORS":
            out[words[1]] = np.frombuffer(data, ">f4", 3 * n, pos).reshape(n, 3)
            pos += 12 * n
        elif words[0] == "SCALARS":
            if not line().startswith("LOOKUP_TABLE"):
                raise ValueError(f"{path}: SCALARS {words[1]} without its LOOKUP_TABLE line")
            dtype = ">f4" if words[2] == "float" else ">i4"
            components = int(words[3]) if len(words) > 3 else 1
            values = np.frombuffer(data, dtype, components * n, pos)
            out[words[1]] = values.reshape(n, components) if components > 1 else values
            pos += 4 * components * n
        else:
            raise ValueError(f"{path}: unexpected VTK section {text!r}")
    return out


def read_series(particles_dir: pathlib.Path, name: str = "particles.vtk.series") -> list:
    """[(simulated time s, frame path)] of a `.vtk.series` index, in its order."""
    index = pathlib.Path(particles_dir) / name
    try:
        files = json.loads(index.read_text())["files"]
        return [(float(f["time"]), pathlib.Path(particles_dir) / f["name"]) for f in files]
    except (OSError, ValueError, KeyError, TypeError) as error:
        raise ValueError(f"{index}: not a readable .vtk.series index: {error}") from error
