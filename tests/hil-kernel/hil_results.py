"""Reads what the guest left in the results share: junit.xml, summary.txt and per-test logs.

A planned test with no result counts as failed ("missing"): the guest hung or died before it."""
from __future__ import annotations

import dataclasses
import pathlib
import xml.etree.ElementTree as ET


@dataclasses.dataclass
class Outcome:
    status: str        # pass | fail | timeout | missing
    message: str
    log_tail: list[str]


@dataclasses.dataclass
class Report:
    outcomes: dict[str, Outcome]
    summary: str | None

    @property
    def passed(self) -> int:
        return sum(o.status == "pass" for o in self.outcomes.values())

    @property
    def all_passed(self) -> bool:
        return bool(self.outcomes) and self.passed == len(self.outcomes)


def _tail(path: pathlib.Path, n: int = 30) -> list[str]:
    try:
        return path.read_text(errors="replace").splitlines()[-n:]
    except OSError:
        return ["(no log)"]


def read_results(results: pathlib.Path, planned: list[str]) -> Report:
    seen: dict[str, Outcome] = {}
    junit = results / "junit.xml"
    if junit.exists():
        try:
            root = ET.parse(junit).getroot()
        except ET.ParseError as e:
            root = None
            seen["(junit.xml)"] = Outcome("fail", f"unreadable junit.xml: {e}", [])
        for case in (root.iter("testcase") if root is not None else []):
            name = case.get("name", "?")
            fail = case.find("failure")
            if fail is None:
                seen[name] = Outcome("pass", "", [])
            else:
                seen[name] = Outcome(fail.get("type", "fail"), fail.get("message", ""),
                                     _tail(results / "logs" / f"{name}.log"))
    outcomes = {}
    for name in planned:
        outcomes[name] = seen.pop(name, None) or Outcome(
            "missing", "no result: the guest stopped before this test finished",
            _tail(results / "logs" / f"{name}.log"))
    outcomes.update(seen)  # anything unexpected (a broken junit.xml) is reported too
    summary_file = results / "summary.txt"
    summary = summary_file.read_text().strip() if summary_file.exists() else None
    return Report(outcomes=outcomes, summary=summary)
