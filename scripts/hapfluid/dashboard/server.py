"""haptic-dashboard: one read-only web page of a running stack, for the rig operator.

It runs `haptic-status` (the C++ observer that maps every segment read-only and trusts nothing
in them) and serves what it prints: the page at /, the newest snapshot and the last 10 s of
wrenches at /api/status, the same live over a WebSocket at /ws (at most 30 updates a second),
and the flight-recorder dumps at /flight/<name>.csv. Every route is a GET; the WebSocket only
sends. Nothing here opens a segment, a device or a socket to the stack, so nothing on the page
can move a motor, clear a fault or change a limit. It listens on 127.0.0.1:8642 unless told
(rig key dashboard.address); reach it from another machine through an SSH tunnel.

  haptic-dashboard [--rig FILE] [--shm-prefix P] [--listen HOST:PORT] [--flight-dir DIR] [--trust-user U]
"""
from __future__ import annotations

import argparse
import asyncio
import collections
import json
import logging
import os
import pathlib
import sys
import time
import tomllib

from aiohttp import WSCloseCode, WSMsgType, web

from ..paths import BIN

STATIC = pathlib.Path(__file__).parent / "static"
HISTORY_S = 10.0
MAX_RATE_HZ = 30.0
DEFAULT_LISTEN = "127.0.0.1:8642"
log = logging.getLogger("haptic-dashboard")


def point(snapshot: dict) -> dict:
    """What the plots keep of one snapshot: time and each device's wrenches and position."""
    return {"t": snapshot["now_ns"] * 1e-9,
            "devices": [{k: d[k] for k in ("command_force_n", "command_torque_nm", "hand_force_n", "hand_torque_nm",
                                           "sim_force_n", "sim_torque_nm", "sim_valid", "position_m")}
                        for d in snapshot.get("devices", [])]}


class Observer:
    """Runs haptic-status and keeps its newest snapshot and the last HISTORY_S of points. Restarts
    it should it ever end; until it prints, the snapshot says the observer is starting."""

    def __init__(self, binary: pathlib.Path, prefix: str, rate_hz: float, flight_dir: pathlib.Path | None,
                 trust_user: str | None = None):
        self.binary, self.prefix, self.rate_hz, self.flight_dir = binary, prefix, rate_hz, flight_dir
        self.trust = ("--trust-user", trust_user) if trust_user else ()
        self.snapshot: dict = {"observer": "starting", "prefix": prefix}
        self.history: collections.deque = collections.deque()
        self.listeners: set[asyncio.Queue] = set()
        self.process: asyncio.subprocess.Process | None = None
        self.lines = 0

    async def run(self):
        while True:
            try:
                self.process = await asyncio.create_subprocess_exec(
                    str(self.binary), "--shm-prefix", self.prefix, "--rate", str(self.rate_hz), *self.trust,
                    stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE, limit=1 << 20)
            except OSError as e:
                self.snapshot = {"observer": f"cannot run {self.binary}: {e}", "prefix": self.prefix}
                await asyncio.sleep(2)
                continue
            async for raw in self.process.stdout:
                try:
                    snapshot = json.loads(raw)
                except ValueError:
                    continue
                self.take(snapshot)
            code = await self.process.wait()
            err = (await self.process.stderr.read()).decode(errors="replace").strip()
            self.snapshot = {**self.snapshot, "observer": f"haptic-status exited {code}: {err[-300:]}"}
            log.warning("haptic-status exited %s%s; restarting it", code, f": {err[-300:]}" if err else "")
            await asyncio.sleep(1)

    def take(self, snapshot: dict):
        snapshot["observer"] = "live"
        snapshot["flight_dumps"] = self.flight_dumps()
        self.snapshot = snapshot
        self.lines += 1
        p = point(snapshot)
        self.history.append(p)
        while self.history and p["t"] - self.history[0]["t"] > HISTORY_S:
            self.history.popleft()
        message = json.dumps({"snapshot": snapshot, "point": p})
        for q in list(self.listeners):
            if q.full():  # a slow browser skips updates, it never holds this loop up
                q.get_nowait()
            q.put_nowait(message)

    def flight_dumps(self) -> list[dict]:
        if not self.flight_dir or not self.flight_dir.is_dir():
            return []
        dumps = []
        for f in sorted(self.flight_dir.glob("*.csv"), key=lambda f: f.stat().st_mtime, reverse=True)[:50]:
            st = f.stat()
            dumps.append({"name": f.name, "bytes": st.st_size, "age_s": round(time.time() - st.st_mtime, 1)})
        return dumps

    async def stop(self):
        if self.process and self.process.returncode is None:
            self.process.terminate()
            await self.process.wait()


def make_app(observer: Observer) -> web.Application:
    app = web.Application()

    async def index(request):
        return web.FileResponse(STATIC / "index.html")

    async def status(request):
        return web.json_response({"snapshot": observer.snapshot, "history": list(observer.history)})

    async def flight(request):
        name = request.match_info["name"]
        # A dump's file name only: no path, nothing outside the flight directory.
        if observer.flight_dir is None or "/" in name or name.startswith(".") or not name.endswith(".csv"):
            raise web.HTTPNotFound()
        path = observer.flight_dir / name
        if not path.is_file():
            raise web.HTTPNotFound()
        return web.FileResponse(path, headers={"Content-Disposition": f'attachment; filename="{name}"',
                                               "Content-Type": "text/csv"})

    sockets: set = set()

    async def websocket(request):
        ws = web.WebSocketResponse(heartbeat=10)
        await ws.prepare(request)
        sockets.add(ws)
        queue: asyncio.Queue = asyncio.Queue(maxsize=4)
        observer.listeners.add(queue)
        await ws.send_str(json.dumps({"snapshot": observer.snapshot, "history": list(observer.history)}))

        async def drain_incoming():  # the page sends nothing that means anything: read and drop
            async for msg in ws:
                if msg.type in (WSMsgType.CLOSE, WSMsgType.ERROR):
                    break
        reader = asyncio.ensure_future(drain_incoming())
        try:
            while not ws.closed:
                getter = asyncio.ensure_future(queue.get())
                done, _ = await asyncio.wait({getter, reader}, return_when=asyncio.FIRST_COMPLETED)
                if reader in done:
                    getter.cancel()
                    break
                await ws.send_str(getter.result())
        except (ConnectionResetError, asyncio.CancelledError):
            pass
        finally:
            observer.listeners.discard(queue)
            sockets.discard(ws)
            reader.cancel()
        return ws

    app.router.add_get("/", index)
    app.router.add_get("/api/status", status)
    app.router.add_get("/flight/{name}", flight)
    app.router.add_get("/ws", websocket)
    app.router.add_static("/static/", STATIC)

    async def start_observer(app):
        app["observer_task"] = asyncio.ensure_future(observer.run())

    async def stop_observer(app):
        app["observer_task"].cancel()
        await observer.stop()

    async def close_pages(app):  # an open page must not hold the server's stop (SIGINT, systemctl stop)
        for ws in list(sockets):
            await ws.close(code=WSCloseCode.GOING_AWAY, message=b"haptic-dashboard stops")
    app.on_startup.append(start_observer)
    app.on_shutdown.append(close_pages)
    app.on_cleanup.append(stop_observer)
    return app


def parse_listen(text: str, where: str) -> tuple[str, int]:
    host, _, port = text.rpartition(":")
    if not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise SystemExit(f"haptic-dashboard: {where} = {text!r}: not HOST:PORT (e.g. {DEFAULT_LISTEN})")
    return host.strip("[]"), int(port)


def main(argv=None):
    ap = argparse.ArgumentParser(prog="haptic-dashboard", description=__doc__.split("\n\n")[0])
    ap.add_argument("--rig", type=pathlib.Path, help="take the shm prefix ([rt.shm] prefix) and the address "
                                                     "([dashboard] address) from this rig file")
    ap.add_argument("--shm-prefix", help="shared-memory prefix of the stack (default: the rig's, else hapfluid)")
    ap.add_argument("--listen", help=f"HOST:PORT to serve on (default: the rig's, else {DEFAULT_LISTEN})")
    ap.add_argument("--flight-dir", type=pathlib.Path, help="haptic-rt's --flight-dir, whose dumps the page offers")
    ap.add_argument("--trust-user", help="the services' user, whose segments to read when this runs as a user of "
                                         "its own (its systemd unit: hapfluid)")
    ap.add_argument("--rate", type=float, default=MAX_RATE_HZ, help="updates per second (at most 30)")
    ap.add_argument("--status-binary", type=pathlib.Path, default=BIN / "haptic-status",
                    help="the haptic-status to run (default: %(default)s)")
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="haptic-dashboard: %(message)s")
    if not 0 < args.rate <= MAX_RATE_HZ:
        ap.error(f"--rate {args.rate}: must be in (0, {MAX_RATE_HZ:g}]")
    rig = {}
    if args.rig:
        try:
            rig = tomllib.loads(args.rig.read_text())
        except (OSError, ValueError) as e:  # tomllib.TOMLDecodeError is a ValueError, with line and column
            ap.error(f"--rig {args.rig}: {e}")
    prefix = args.shm_prefix or rig.get("rt", {}).get("shm", {}).get("prefix") or "hapfluid"
    listen = args.listen or rig.get("dashboard", {}).get("address") or DEFAULT_LISTEN
    host, port = parse_listen(listen, "--listen" if args.listen else f"{args.rig}: dashboard.address")
    if not os.access(args.status_binary, os.X_OK):
        ap.error(f"--status-binary {args.status_binary}: not an executable (run `make`)")
    observer = Observer(args.status_binary, prefix, args.rate, args.flight_dir, args.trust_user)
    log.info("serving the stack with shm prefix %s on http://%s:%d/", prefix, host, port)
    sys.stdout.flush()
    web.run_app(make_app(observer), host=host, port=port, print=None, access_log=None)


if __name__ == "__main__":
    main()
