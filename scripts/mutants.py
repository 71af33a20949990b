#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""The mutation check: plausible bugs put into the kernel one at a time; each must make a test fail.

    python3 scripts/mutants.py                 # all mutants of tests/mutants/mutants.json
    python3 scripts/mutants.py --only rms-without-sqrt auto-anchor-wrong-rod-end
    python3 scripts/mutants.py --list          # the mutants, nothing built

The list (tests/mutants/mutants.json) names, per mutant, a file of the kernel, one exact piece of
its text (found exactly once), what replaces it, the kind of bug it stands for, and a ctest regex
of the tests expected to catch it. For each mutant this script changes that one piece, rebuilds
the tree build-mutants/ (the suite without the daemon and the layer probes: the kernel's bugs
are the kernel's tests' business), runs the expected tests, and if none of them fails the whole
suite. A mutant is *caught* when a test fails (a test that hangs until ctest's timeout counts) and
*survives* when every test passes; a mutant that does not compile is an error in the list.
The source is restored after every mutant, also on Ctrl-C, and a run that was killed outright is
restored at the next start from build-mutants/applied.json.

Exit status: 0 when every mutant was caught, 1 otherwise. The table of results is printed and
written to build-mutants/mutants.md (docs/testing.md keeps the last one).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
LIST = ROOT / "tests" / "mutants" / "mutants.json"
BUILD = ROOT / "build-mutants"
JOURNAL = BUILD / "applied.json"
TEST_TIMEOUT = 300  # seconds per test: a mutant that makes a test hang is caught by this


def load() -> list[dict]:
    mutants = json.loads(LIST.read_text())
    ids = set()
    for m in mutants:
        for key in ("id", "layer", "file", "find", "replace", "bug", "tests"):
            if not isinstance(m.get(key), str) or not m[key]:
                sys.exit(f"mutants: {LIST}: {m.get('id', '?')}: field '{key}' missing")
        if m["id"] in ids:
            sys.exit(f"mutants: {LIST}: id '{m['id']}' twice")
        ids.add(m["id"])
        text = (ROOT / m["file"]).read_text()
        count = text.count(m["find"])
        if count != 1:
            sys.exit(f"mutants: {m['id']}: the text to change occurs {count} times in {m['file']}")
        re.compile(m["tests"])
    return mutants


def restore_from_journal() -> None:
    if not JOURNAL.exists():
        return
    applied = json.loads(JOURNAL.read_text())
    path = ROOT / applied["file"]
    path.write_bytes(bytes.fromhex(applied["original"]))
    JOURNAL.unlink()
    print(f"mutants: restored {applied['file']} from an interrupted run", file=sys.stderr)


class Applied:
    """One mutant in the source for the duration of a `with` block; restored on any exit."""

    def __init__(self, mutant: dict):
        self.path = ROOT / mutant["file"]
        self.mutant = mutant

    def __enter__(self):
        self.original = self.path.read_bytes()
        JOURNAL.write_text(json.dumps({"file": self.mutant["file"], "original": self.original.hex()}))
        text = self.original.decode()
        self.path.write_text(text.replace(self.mutant["find"], self.mutant["replace"], 1))
        return self

    def __exit__(self, *exc):
        self.path.write_bytes(self.original)
        JOURNAL.unlink(missing_ok=True)
        return False


def run(command: list[str], log: Path) -> int:
    with open(log, "w") as out:
        return subprocess.run(command, cwd=ROOT, stdout=out, stderr=subprocess.STDOUT).returncode


def build(log: Path) -> bool:
    return run(["cmake", "--build", str(BUILD), "-j", str(os.cpu_count() or 2)], log) == 0


def failed_tests(log: Path) -> list[str]:
    """The names ctest lists under "The following tests FAILED:" (failed, timed out, crashed)."""
    text = log.read_text()
    section = text.split("The following tests FAILED:", 1)
    return re.findall(r"^\s*\d+ - (\S+) \(", section[1], re.M) if len(section) == 2 else []


def ctest(regex: str | None, log: Path) -> int:
    command = ["ctest", "--test-dir", str(BUILD), "-j", str(os.cpu_count() or 2), "-LE", "cluster",
               "--timeout", str(TEST_TIMEOUT), "--output-on-failure"]
    if regex:
        command += ["-R", regex]
    else:
        command += ["--stop-on-failure"]
    return run(command, log)


def configure() -> None:
    BUILD.mkdir(exist_ok=True)
    subprocess.run(["cmake", "-S", str(ROOT), "-B", str(BUILD), "-G", "Ninja",
                    "-DCMAKE_BUILD_TYPE=RelWithDebInfo", "-DGRIDSHELL_BUILD_SERVER=OFF",
                    "-DGRIDSHELL_LAYER_TESTS=OFF"], check=True, stdout=subprocess.DEVNULL)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", nargs="+", metavar="ID", help="run these mutants only")
    parser.add_argument("--list", action="store_true", help="print the mutants and stop")
    args = parser.parse_args()
    BUILD.mkdir(exist_ok=True)
    restore_from_journal()
    mutants = load()
    if args.only:
        unknown = set(args.only) - {m["id"] for m in mutants}
        if unknown:
            sys.exit(f"mutants: unknown id(s): {', '.join(sorted(unknown))}")
        mutants = [m for m in mutants if m["id"] in args.only]
    if args.list:
        for m in mutants:
            print(f"{m['id']:45} {m['layer']:12} {m['file']}\n    {m['bug']}")
        return 0
    # A TERM leaves like Ctrl-C, through the `with` block that restores the file.
    def terminated(signum, frame):
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, terminated)

    configure()
    logs = BUILD / "mutant-logs"
    logs.mkdir(exist_ok=True)
    started = time.monotonic()
    print("mutants: building the unmutated tree and running the whole suite once", flush=True)
    if not build(logs / "baseline-build.log"):
        sys.exit(f"mutants: the unmutated tree does not build ({logs / 'baseline-build.log'})")
    if ctest(None, logs / "baseline-tests.log") != 0:
        sys.exit(f"mutants: the unmutated suite fails ({logs / 'baseline-tests.log'})")
    print(f"mutants: baseline passed in {time.monotonic() - started:.0f} s", flush=True)

    rows = []
    for k, m in enumerate(mutants, 1):
        t0 = time.monotonic()
        build_log, test_log = logs / f"{m['id']}.build.log", logs / f"{m['id']}.tests.log"
        with Applied(m):
            if not build(build_log):
                outcome, caught_by = "does not compile", []
            elif ctest(m["tests"], test_log) != 0:
                outcome, caught_by = "caught", failed_tests(test_log)
            elif ctest(None, test_log) != 0:
                outcome, caught_by = "caught (whole suite)", failed_tests(test_log)
            else:
                outcome, caught_by = "SURVIVED", []
        seconds = time.monotonic() - t0
        rows.append((m, outcome, caught_by, seconds))
        shown = ", ".join(caught_by[:3]) + (f" and {len(caught_by) - 3} more" if len(caught_by) > 3 else "")
        print(f"mutants: [{k}/{len(mutants)}] {m['id']}: {outcome}"
              f"{' by ' + shown if shown else ''} ({seconds:.0f} s)", flush=True)
    # Rebuild the unmutated tree, so that build-mutants/ holds what the source says.
    build(logs / "final-build.log")

    caught = sum(1 for _, outcome, _, _ in rows if outcome.startswith("caught"))
    table = ["| mutant | layer | bug | outcome | failing tests |", "|---|---|---|---|---|"]
    for m, outcome, caught_by, _ in rows:
        tests = ", ".join(f"`{t}`" for t in caught_by[:3]) + (
            f" and {len(caught_by) - 3} more" if len(caught_by) > 3 else "")
        table.append(f"| `{m['id']}` | {m['layer']} | {m['bug']} | {outcome} | {tests} |")
    summary = (f"{caught} of {len(rows)} mutants caught, in {time.monotonic() - started:.0f} s "
               f"({time.strftime('%Y-%m-%d')})")
    (BUILD / "mutants.md").write_text(summary + "\n\n" + "\n".join(table) + "\n")
    print("\n" + summary + "\n\n" + "\n".join(table))
    return 0 if caught == len(rows) else 1


if __name__ == "__main__":
    sys.exit(main())
