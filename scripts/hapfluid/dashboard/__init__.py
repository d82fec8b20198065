"""haptic-dashboard: a live, read-only web page of a running stack for the rig operator
(server.py; the page in static/)."""
import signal
import sys


def _stop(signum, frame):
    raise KeyboardInterrupt


def run(argv=None) -> int:
    """The command: a stop asked for while the server still starts (its imports alone take a
    second or more on a loaded machine) must neither be lost nor end in a traceback. SIGINT and
    SIGTERM raise KeyboardInterrupt until aiohttp's own handlers take over, even when the parent
    left SIGINT ignored (a background job of a non-interactive shell), and the start ends quietly."""
    signal.signal(signal.SIGINT, _stop)
    signal.signal(signal.SIGTERM, _stop)
    print("haptic-dashboard: starting", file=sys.stderr, flush=True)
    try:
        from .server import main
        main(argv)
    except KeyboardInterrupt:
        print("haptic-dashboard: stopped while starting", file=sys.stderr, flush=True)
    return 0
