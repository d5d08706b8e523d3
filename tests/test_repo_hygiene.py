# SPDX-License-Identifier: LGPL-2.1-or-later
"""Repository hygiene: the tracked files speak of the product as it is, and carry a licence line.

* No development history in the text: no "session <n>", no "issue <n>" / "issue #<n>" (history
  lives in git and in CHANGELOG.md), and no path of a development machine (a work folder, a home
  folder, a temporary folder).
* Every source file (.py, .cpp, .h, .sh, CMakeLists.txt) has the line
  "SPDX-License-Identifier: LGPL-2.1-or-later" in its first 3 lines.

Files: what ``git ls-files`` lists, read from the working tree; binary files, test data
(``tests/data/``) and ``resources/`` are skipped. Skipped when the checkout has no git.
"""

import os
import re
import shutil
import subprocess

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
THIS_FILE = os.path.relpath(os.path.abspath(__file__), ROOT).replace(os.sep, "/")
SKIPPED_FOLDERS = ("tests/data/", "resources/")
SPDX = "SPDX-License-Identifier: LGPL-2.1-or-later"
SOURCE_SUFFIXES = (".py", ".cpp", ".h", ".sh")

#: What may stand between a word and its number: spaces, or a line break with a comment marker
#: ("session\n// 22" in a wrapped comment).
_GAP = r"(?:[ \t]|\n[ \t]*(?://+|#+|\*|<!--)?[ \t]*)+#?"
#: (what it is, pattern).
HISTORY_PATTERNS = [
    ("a session number", re.compile(r"\b[Ss]ession" + _GAP + r"\d")),
    ("an issue number", re.compile(r"\b[Ii]ssue" + _GAP + r"\d")),
    ("a machine path", re.compile(r"/work/|/home/[a-z]|/tmp/[a-z]")),
]


def _tracked_files():
    if shutil.which("git") is None or not os.path.exists(os.path.join(ROOT, ".git")):
        pytest.skip("not a git checkout")
    out = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True).stdout
    return [p for p in out.decode("utf-8").split("\0") if p]


def _text(path):
    """The file's text, or None for a binary file (NUL bytes or not UTF-8) or a missing one."""
    full = os.path.join(ROOT, path)
    if not os.path.isfile(full):
        return None
    with open(full, "rb") as f:
        data = f.read()
    if b"\0" in data:
        return None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return None


def _checked_files():
    return [p for p in _tracked_files() if not p.startswith(SKIPPED_FOLDERS)]


def test_no_history_or_machine_paths_in_tracked_text():
    findings = []
    for path in _checked_files():
        if path == THIS_FILE:
            continue
        text = _text(path)
        if text is None:
            continue
        for what, pattern in HISTORY_PATTERNS:
            for m in pattern.finditer(text):
                number = text.count("\n", 0, m.start()) + 1
                line = text.splitlines()[number - 1]
                findings.append(f"{path}:{number}: {what} ({m.group(0)!r}): {line.strip()[:100]}")
    assert not findings, (
        "tracked text should describe the product as it is (history belongs in git and "
        "CHANGELOG.md; no paths of a development machine):\n" + "\n".join(findings))


def test_source_files_carry_the_spdx_line():
    missing = []
    for path in _checked_files():
        name = os.path.basename(path)
        if not (path.endswith(SOURCE_SUFFIXES) or name == "CMakeLists.txt"):
            continue
        text = _text(path)
        if text is None:
            continue
        if not any(SPDX in line for line in text.splitlines()[:3]):
            missing.append(path)
    assert not missing, (f"{len(missing)} source files lack '{SPDX}' in their first 3 lines:\n"
                         + "\n".join(missing))
