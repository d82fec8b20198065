"""haptic-dashboard in a real browser (Debian's chromium, driven by Playwright) beside a live stack
with a fake device: the page lists the rig's device and fills its force plot, shows the force the
loop sent as the trace recorded it, shows a killed sim's fault and the zeroed force, clears it when
the sim returns, shows a device that went silent as a link fault, and offers nothing that could
send anything to the stack. The page's screenshots are kept in out/test-artefacts/dashboard/."""
import csv
import io
import json
import shutil
import signal
import socket
import sys
import time
import urllib.error
import urllib.request

import pytest

from hil_stack import Stack

playwright = pytest.importorskip("playwright.sync_api", reason="playwright is in the project venv (install-deps)")

CHROMIUM = shutil.which("chromium")
LOAD = "0,0,2"  # the stand-in's wrench (N): steady, so the hand engages through the engage gate
LOAD_N = 2.0


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def device_state(page) -> dict:
    """What the page shows of the first device, read from the page itself."""
    return page.evaluate("""() => {
        const card = document.querySelector('.device');
        if (!card) return null;
        const f = card.querySelector('.force-now');
        return {name: card.dataset.name, link: card.querySelector('.link').textContent,
                faults: card.querySelector('.faults').textContent,
                engage: card.querySelector('.engage').textContent,
                fx: +f.dataset.fx, fy: +f.dataset.fy, fz: +f.dataset.fz, tick: +f.dataset.tick,
                points: +card.querySelector('.force-plot').dataset.points,
                banner: document.getElementById('banner').hidden ? '' : document.getElementById('banner').textContent};
    }""")


def wait_page(page, what, predicate, timeout_s=30.0):
    """Until the page shows what predicate wants; returns (state, seconds waited)."""
    t0 = time.monotonic()
    while True:
        state = device_state(page)
        if state and predicate(state):
            return state, time.monotonic() - t0
        assert time.monotonic() - t0 < timeout_s, f"the page never showed {what}; it shows {state}"
        page.wait_for_timeout(20)


@pytest.fixture
def stack(binary, tmp_path):
    s = Stack(binary, tmp_path, tag="dashboard")
    yield s
    s.close()


def test_the_operators_page_follows_the_stack_and_sends_it_nothing(stack, binary, source_dir):
    artefacts = source_dir / "out" / "test-artefacts" / "dashboard"
    artefacts.mkdir(parents=True, exist_ok=True)
    assert CHROMIUM, "chromium is missing (scripts/install-deps.sh)"
    stack.fake_device("hand", motion="hold", extra=("--inject-on-signal", "--silent-after", "0"))
    stack.rt(settle_s=0)
    stack.standin("--rate", "200", "--force", LOAD)
    port = free_port()
    stack._start("dashboard", [sys.executable, "-m", "hapfluid.dashboard", "--shm-prefix", stack.prefix,
                                           "--listen", f"127.0.0.1:{port}", "--flight-dir", stack.dir / "flight",
                                           "--status-binary", binary("haptic-status")])
    url = f"http://127.0.0.1:{port}/"
    stack.wait_until("the dashboard answers", lambda: _answers(url), watch=("dashboard",))

    with playwright.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        page = browser.new_page(viewport={"width": 1400, "height": 1000})
        sent_by_page = []
        page.on("websocket", lambda ws: ws.on("framesent", lambda payload: sent_by_page.append(payload)))
        page.on("request", lambda r: sent_by_page.append(f"{r.method} {r.url}") if r.method != "GET" else None)
        page.goto(url)
        opened = time.monotonic()
        # The rig's device, and its force plot filling, within 2 s of the page opening.
        state, _ = wait_page(page, "the device and its force plot", lambda s: s["name"] == "hand" and s["points"] >= 2,
                             timeout_s=2.0)
        filled_s = time.monotonic() - opened
        # The hand engaged under the stand-in's steady load.
        state, _ = wait_page(page, f"the hand engaged at {LOAD_N} N",
                             lambda s: s["engage"] == "engaged" and abs(s["fz"] - LOAD_N) < 0.05)
        page.screenshot(path=str(artefacts / "engaged.png"), full_page=True)

        # The force shown is the force the loop sent at the tick the page names (the trace's).
        shown = [state]
        while len(shown) < 5:  # five updates, each of a later tick
            state, _ = wait_page(page, "a newer tick", lambda s: s["tick"] > shown[-1]["tick"])
            shown.append(state)
        stack.wait_until("the trace has the shown ticks",
                         lambda: max(_trace_rows(stack), default=0) >= shown[-1]["tick"], watch=("rt",))
        rows = _trace_rows(stack)
        for s in shown:
            row = rows[s["tick"]]
            for axis in "xyz":
                assert abs(s[f"f{axis}"] - row[f"d0_f{axis}"]) <= 0.05, (s, {k: row[k] for k in ("d0_fx", "d0_fy", "d0_fz")})

        # A killed sim: its fault and the zeroed force within 1 s.
        stack.kill("standin")
        killed = time.monotonic()
        state, _ = wait_page(page, "the sim's fault and zero force",
                             lambda s: "sim_stale" in s["faults"] and s["fx"] == s["fy"] == s["fz"] == 0, timeout_s=5)
        zeroed_s = time.monotonic() - killed
        assert zeroed_s <= 1.0, f"the page showed the sim fault and zero force {zeroed_s:.2f} s after the kill"
        assert "haptic-sim" in state["banner"]
        page.screenshot(path=str(artefacts / "sim-killed.png"), full_page=True)

        # The sim returns: the fault clears, the banner goes.
        stack.standin("--rate", "200", "--force", LOAD, name="standin2")
        wait_page(page, "the sim fault cleared", lambda s: "sim_stale" not in s["faults"] and not s["banner"])

        # The device stops answering: a link fault.
        stack.procs["fake-hand"].send_signal(signal.SIGUSR1)
        state, _ = wait_page(page, "a link fault", lambda s: s["link"] == "link fault" and "link_timeout" in s["faults"])
        page.screenshot(path=str(artefacts / "link-fault.png"), full_page=True)

        # Nothing on the page can send anything: no control of any kind, and the page sent
        # nothing but GETs and no WebSocket frame.
        controls = page.evaluate("document.querySelectorAll('button, input, select, textarea, form').length")
        assert controls == 0
        assert sent_by_page == []
        # An open page does not hold the server up when it is stopped (SIGINT, systemctl stop).
        assert stack.stop("dashboard", timeout=5) == 0
        wait_page(page, "the page saying it lost the server",
                  lambda s: page.text_content("#connection").startswith("disconnected"))
        browser.close()

    stack._start("dashboard2", [sys.executable, "-m", "hapfluid.dashboard", "--shm-prefix", stack.prefix,
                                "--listen", f"127.0.0.1:{port}", "--flight-dir", stack.dir / "flight",
                                "--status-binary", binary("haptic-status")])
    stack.wait_until("the restarted dashboard answers", lambda: _answers(url), watch=("dashboard2",))
    # The flight recorder dumped at the faults; the page offers each dump as it is on disk.
    with urllib.request.urlopen(url + "api/status", timeout=5) as r:
        dumps = json.load(r)["snapshot"]["flight_dumps"]
    assert dumps, "no flight-recorder dump listed after the sim and link faults"
    with urllib.request.urlopen(url + "flight/" + dumps[0]["name"], timeout=5) as r:
        assert r.read() == (stack.dir / "flight" / dumps[0]["name"]).read_bytes()
    # The server takes nothing but GET, and offers no file outside the flight directory.
    for method in ("POST", "PUT", "DELETE", "PATCH"):
        for path in ("", "api/status", "ws", "flight/x.csv"):
            assert _status(url + path, method) == 405, (method, path)
    assert _status(url + "flight/..%2Frig.toml") == 404
    assert _status(url + "flight/rig.toml") == 404
    print(f"dashboard: force plot filled {filled_s:.2f} s after the page opened; sim fault and zero force shown "
          f"{zeroed_s:.2f} s after the kill; screenshots in {artefacts}")
    assert stack.stop("dashboard2") == 0


def _answers(url) -> bool:
    try:
        with urllib.request.urlopen(url + "api/status", timeout=2) as r:
            return json.load(r)["snapshot"].get("observer") == "live"
    except (OSError, ValueError):
        return False


def _status(url, method="GET") -> int:
    try:
        with urllib.request.urlopen(urllib.request.Request(url, method=method), timeout=5) as r:
            return r.status
    except urllib.error.HTTPError as e:
        return e.code


def _trace_rows(stack) -> dict:
    """haptic-rt's trace as far as it is written (a line in progress is left out), by tick."""
    path = stack.dir / "rt-trace.csv"
    if not path.exists():
        return {}
    text = path.read_text()
    rows = csv.DictReader(io.StringIO(text[:text.rfind("\n") + 1]))
    return {int(r["tick"]): {k: float(v) for k, v in r.items()} for r in rows}
