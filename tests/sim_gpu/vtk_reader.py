"""Reads the legacy binary VTK frames haptic-sim writes (POLYDATA points + point data)."""
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
    assert header[0].startswith("# vtk DataFile"), header
    assert header[2] == "BINARY" and header[3] == "DATASET POLYDATA", header
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
            assert line().startswith("LOOKUP_TABLE")
            dtype = ">f4" if words[2] == "float" else ">i4"
            components = int(words[3]) if len(words) > 3 else 1
            values = np.frombuffer(data, dtype, components * n, pos)
            out[words[1]] = values.reshape(n, components) if components > 1 else values
            pos += 4 * components * n
        else:
            raise ValueError(f"{path}: unexpected VTK section {text!r}")
    return out
