#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""Adds SPDX licence identifiers to gridshell's tracked source files.

    python3 scripts/spdx.py            # add the missing lines (idempotent)
    python3 scripts/spdx.py --check    # only list the files lacking one; exit 1 if any
    python3 scripts/spdx.py --dry-run  # print what would be changed, change nothing

Which files, and which line:

  *.cpp *.h *.hpp *.cc *.proto *.ts *.mjs "// SPDX-License-Identifier: GPL-3.0-or-later", first line
  CMakeLists.txt *.cmake *.sh *.py, and
  any other file starting with "#!"       "# SPDX-License-Identifier: GPL-3.0-or-later", first
                                          line, or right after the shebang (and after a Python
                                          coding line, which must stay on line 1 or 2)

A file that already has an SPDX-License-Identifier line near its top is left alone, whatever
identifier it names. Third-party files get their own licence (THIRD_PARTY below), and only when
they carry no licence header at all; generated files and build trees are skipped (EXCLUDED).

The file list is `git ls-files` of the repository holding this script (or of --root). Outside a
git work tree (e.g. an exported `git archive`), every file under the root is considered, minus
build trees and dot folders other than .ci.

Line endings (LF / CRLF), a UTF-8 byte order mark and file modes are preserved.
"""

from __future__ import annotations

import argparse
import fnmatch
import os
import re
import subprocess
import sys
from pathlib import Path

PROJECT_LICENSE = "GPL-3.0-or-later"
TAG = b"SPDX-License-Identifier:"

# Third-party files: path -> (licence, extra header lines). They get the line only if they have
# no licence header of their own (a "Copyright" or "License" mention in their first lines).
THIRD_PARTY: dict[str, tuple[str, list[str]]] = {
    # Restates gRPC's standard health checking protocol (grpc/grpc-proto,
    # grpc/health/v1/health.proto, Apache-2.0); kept under gRPC's licence with its attribution.
    "proto/grpc/health/v1/health.proto": ("Apache-2.0",
                                          ["SPDX-FileCopyrightText: 2015 The gRPC Authors"]),
}

# Never touched: generated code, vendored trees, build output.
EXCLUDED = [
    "*.pb.h", "*.pb.cc", "*.grpc.pb.h", "*.grpc.pb.cc",
    "build/*", "build-*/*", "*/build/*", "generated/*", "*/generated/*",
    "third_party/*", "*/third_party/*", "node_modules/*", "*/node_modules/*",
]

SLASH_SUFFIXES = (".cpp", ".cc", ".cxx", ".h", ".hh", ".hpp", ".proto", ".ts", ".js", ".mjs")
HASH_SUFFIXES = (".cmake", ".sh", ".py")
HASH_NAMES = ("CMakeLists.txt",)

# A licence header already present (third-party files only).
LICENSE_HEADER = re.compile(rb"copyright|licen[cs]ed under|\blicen[cs]e\b", re.IGNORECASE)
PY_CODING = re.compile(rb"^[ \t\f]*#.*?coding[:=][ \t]*[-\w.]+")
HEAD_LINES = 10  # an SPDX line counts if it is within this many lines from the top
LICENSE_HEAD_LINES = 30


def comment_style(path: str, data: bytes) -> str | None:
    """'//' or '#' for the files this script handles, None for the others."""
    name = os.path.basename(path)
    if name.endswith(SLASH_SUFFIXES):
        return "//"
    if name in HASH_NAMES or name.endswith(HASH_SUFFIXES):
        return "#"
    if data.startswith(b"#!"):
        return "#"
    return None


def excluded(path: str) -> bool:
    return any(fnmatch.fnmatch(path, pattern) for pattern in EXCLUDED)


def tracked_files(root: Path) -> list[str]:
    try:
        out = subprocess.run(["git", "-C", str(root), "ls-files", "-z"], check=True,
                             capture_output=True).stdout
        return sorted(p for p in out.decode("utf-8", "surrogateescape").split("\0") if p)
    except (OSError, subprocess.CalledProcessError):
        pass
    files = []
    for folder, dirs, names in os.walk(root):
        rel = os.path.relpath(folder, root)
        dirs[:] = [d for d in dirs
                   if not (d.startswith(".") and d != ".ci")
                   and not (rel == "." and (d == "build" or d.startswith("build-")))]
        for name in names:
            files.append(os.path.normpath(os.path.join(rel, name)))
    return sorted(files)


def has_spdx(data: bytes) -> bool:
    return any(TAG in line for line in data.split(b"\n", HEAD_LINES)[:HEAD_LINES])


def has_license_header(data: bytes) -> bool:
    head = b"\n".join(data.split(b"\n", LICENSE_HEAD_LINES)[:LICENSE_HEAD_LINES])
    return bool(LICENSE_HEADER.search(head))


def with_header(data: bytes, style: str, license_id: str, extra: list[str]) -> bytes:
    """`data` with the SPDX line (and `extra` lines) inserted at the right place."""
    bom = b"\xef\xbb\xbf" if data.startswith(b"\xef\xbb\xbf") else b""
    body = data[len(bom):]
    newline = b"\r\n" if b"\r\n" in body.split(b"\n", 1)[0] + b"\n" else b"\n"
    header = b"".join(f"{style} {text}".encode() + newline
                      for text in [f"SPDX-License-Identifier: {license_id}", *extra])
    lines = body.splitlines(keepends=True)
    keep = 0  # lines that must stay above the header
    if style == "#" and lines and lines[0].startswith(b"#!"):
        keep = 1
        if len(lines) > 1 and PY_CODING.match(lines[1]):
            keep = 2
    elif style == "#" and lines and PY_CODING.match(lines[0]):
        keep = 1
    if keep and not lines[keep - 1].endswith(b"\n"):
        lines[keep - 1] += newline  # a shebang-only file without a final newline
    return bom + b"".join(lines[:keep]) + header + b"".join(lines[keep:])


def plan(root: Path) -> list[tuple[str, str, list[str], str]]:
    """Files lacking an SPDX line: (path, licence, extra lines, comment style)."""
    todo = []
    for rel in tracked_files(root):
        path = root / rel
        if excluded(rel) or path.is_symlink() or not path.is_file():
            continue
        data = path.read_bytes()
        style = comment_style(rel, data)
        if style is None or has_spdx(data):
            continue
        if rel in THIRD_PARTY:
            if has_license_header(data):
                continue  # keeps its own licence header
            license_id, extra = THIRD_PARTY[rel]
        else:
            license_id, extra = PROJECT_LICENSE, []
        todo.append((rel, license_id, extra, style))
    return todo


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--check", action="store_true",
                        help="list the files lacking an SPDX line and exit 1 if there are any")
    parser.add_argument("--dry-run", action="store_true", help="print the changes, make none")
    parser.add_argument("--root", type=Path, default=Path(__file__).resolve().parent.parent,
                        help="repository root (default: the one holding this script)")
    args = parser.parse_args()
    root = args.root.resolve()

    todo = plan(root)
    if args.check:
        for rel, license_id, _, _ in todo:
            print(f"{rel}: no SPDX-License-Identifier (expected {license_id})")
        if todo:
            print(f"spdx: {len(todo)} file(s) lack an SPDX line; run scripts/spdx.py",
                  file=sys.stderr)
        return 1 if todo else 0

    for rel, license_id, extra, style in todo:
        print(f"{'would add' if args.dry_run else 'added'} {license_id}: {rel}")
        if args.dry_run:
            continue
        path = root / rel
        data = path.read_bytes()
        with open(path, "r+b") as f:  # in place: keeps mode, owner and links
            f.write(with_header(data, style, license_id, extra))
            f.truncate()
    if not todo:
        print("spdx: every file has an SPDX line")
    return 0


if __name__ == "__main__":
    sys.exit(main())
