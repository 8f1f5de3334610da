#!/usr/bin/env python3
"""Runs the shell commands that the docs show (ctest label `docs`).

    run_docs.py --source SRC --build BUILD [--list] FILE.md...

Every fenced block whose info string is `sh`, `bash`, `shell` or `console`
in the given Markdown files runs, in the file's order, with `bash -e -o
pipefail`, in a scratch directory where the source tree's top-level entries
are symbolic links (so `examples/...`, `scripts/...` and `.venv` work as
written and what a command writes stays out of the tree) and `build` links
to the build tree; `. scripts/mpi-env` is sourced first. Blocks of one file
share that directory, so a block may read what an earlier one wrote. A
`console` block's commands are its lines that start with `$ ` (the others
are output).

Markers, an HTML comment on the line(s) just before the block (blank lines
between are allowed); they are invisible on a rendered page:

    <!-- docs-test: skip REASON -->         the block does not run; REASON is required
    <!-- docs-test: sub OLD => NEW -->      run it with the text OLD replaced by NEW
                                            (smaller sizes; repeatable, each must match)
    <!-- docs-test: timeout SECONDS -->     the block's time limit (default 120 s)

An indented block (four spaces, after a blank line) whose first line looks
like a command (build/..., scripts/..., .venv/..., mpirun, cmake, ctest,
catchup-..., python3, bash, cc, gfortran, apt-get, VAR=... command) is an
error: fence it as `sh` so that it runs, or mark it skipped. A new block
is thus picked up without touching the tests.
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile
import time

SHELLS = {"sh", "bash", "shell", "console"}
MARK = re.compile(r"^<!--\s*docs-test:\s*(skip|sub|timeout)\b\s*(.*?)\s*-->\s*$")
COMMANDISH = re.compile(r"^(build/|scripts/|\.venv/|\./|\. scripts/|mpirun\s|cmake\s|ctest\s|catchup-\w+\s|"
                        r"python3?\s|bash\s|cc\s|gcc\s|gfortran\s|apt-get\s|pip\s|h5dump\s|"
                        r"[A-Z_]+=\S*\s+\S)")


class Block:
    def __init__(self, path, line, lang, text, marks):
        self.path, self.line, self.lang, self.text, self.marks = path, line, lang, text, marks

    def where(self):
        return f"{self.path}:{self.line}"


def parse(path):
    """The fenced shell blocks with their markers, and the errors: unfenced
    command blocks, markers that are malformed or belong to no block."""
    lines = open(path, encoding="utf-8").read().split("\n")
    blocks, errors, marks, i = [], [], [], 0
    while i < len(lines):
        ln = lines[i]
        m = MARK.match(ln.strip())
        if m:
            marks.append((m.group(1), m.group(2), i + 1))
            i += 1
            continue
        if ln.strip().startswith("<!--") and "docs-test" in ln:
            errors.append(f"{path}:{i + 1}: malformed docs-test marker: {ln.strip()}")
        f = re.match(r"^(\s*)(```+|~~~+)\s*([\w+-]*)", ln)
        if f:
            fence, lang, start = f.group(2), f.group(3).lower(), i
            body = []
            i += 1
            while i < len(lines) and not lines[i].strip().startswith(fence):
                body.append(lines[i])
                i += 1
            i += 1
            if lang in SHELLS:
                blocks.append(Block(path, start + 1, lang, "\n".join(body), marks))
            elif marks:
                errors.append(f"{path}:{start + 1}: docs-test marker before a {lang or 'plain'} block, which never runs")
            marks = []
            continue
        if ln.startswith("    ") and ln.strip() and (i == 0 or not lines[i - 1].strip()) and \
                not re.match(r"^\s*([-*+]|\d+\.)\s", lines[i - 1] if i else ""):
            while i < len(lines) and (lines[i].startswith("    ") or not lines[i].strip()):
                cmd = lines[i].strip()
                if COMMANDISH.match(cmd) and not marks_skip(marks):
                    errors.append(f"{path}:{i + 1}: a command in an indented block ({cmd[:50]}...): fence it "
                                  "as ```sh so that the docs test runs it, or mark it <!-- docs-test: skip REASON -->")
                    break
                i += 1
            while i < len(lines) and (lines[i].startswith("    ") or not lines[i].strip()):
                i += 1
            marks = []
            continue
        if ln.strip():
            if marks:
                errors.append(f"{path}:{marks[0][2]}: docs-test marker not followed by a block")
            marks = []
        i += 1
    return blocks, errors


def marks_skip(marks):
    return any(k == "skip" for k, _, _ in marks)


def commands(block):
    if block.lang != "console":
        return block.text
    return "\n".join(ln[2:] for ln in block.text.split("\n") if ln.startswith("$ "))


def prepare(block):
    """The script to run, or (None, reason) for a skipped block."""
    script, timeout = commands(block), 120
    for kind, arg, line in block.marks:
        if kind == "skip":
            if not arg:
                raise ValueError(f"{block.path}:{line}: skip needs a reason")
            return None, arg, timeout
        if kind == "timeout":
            timeout = float(arg)
        if kind == "sub":
            if "=>" not in arg:
                raise ValueError(f"{block.path}:{line}: sub needs OLD => NEW")
            old, new = (x.strip() for x in arg.split("=>", 1))
            if old not in script:
                raise ValueError(f"{block.path}:{line}: sub: '{old}' is not in the block")
            script = script.replace(old, new)
    return script, None, timeout


def scratch(source, build):
    d = tempfile.mkdtemp(prefix="cup_docs_")
    for name in os.listdir(source):
        if name not in ("build", "out", ".git"):
            os.symlink(os.path.join(source, name), os.path.join(d, name))
    os.symlink(build, os.path.join(d, "build"))
    return d


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--source", required=True)
    ap.add_argument("--build", required=True)
    ap.add_argument("--list", action="store_true", help="list the blocks, run nothing")
    ap.add_argument("files", nargs="+")
    a = ap.parse_args()
    source, build = os.path.abspath(a.source), os.path.abspath(a.build)
    failed = ran = skipped = 0
    venv = os.path.join(source, ".venv", "bin", "python")
    has_venv = subprocess.run([venv, "-c", "import h5py, matplotlib, numpy"], capture_output=True).returncode == 0 \
        if os.access(venv, os.X_OK) else False
    if not has_venv and not a.list and any(".venv/" in b.text for f in a.files for b in parse(f)[0]):
        print(f"SKIP: the blocks call .venv/bin/python and {venv} lacks h5py, matplotlib or numpy "
              "(scripts/run-tests or scripts/setup --python makes it)")
        return 77
    for path in a.files:
        blocks, errors = parse(path)
        for e in errors:
            print(f"docs: {e}")
        failed += len(errors)
        work = None if a.list else scratch(source, build)
        for b in blocks:
            try:
                script, reason, timeout = prepare(b)
            except ValueError as e:
                print(f"docs: {e}")
                failed += 1
                continue
            if script is None:
                print(f"docs: {b.where()}: skipped: {reason}")
                skipped += 1
                continue
            if a.list:
                print(f"docs: {b.where()}: would run:\n{script}")
                continue
            t0 = time.time()
            try:
                p = subprocess.run(["bash", "-c", "set -eo pipefail\n. scripts/mpi-env\n" + script], cwd=work,
                                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=timeout)
                ok, out = p.returncode == 0, p.stdout.decode("utf-8", "replace")
            except subprocess.TimeoutExpired as e:
                ok, out = False, (e.stdout or b"").decode("utf-8", "replace") + f"\n(timed out after {timeout:g} s)"
            ran += 1
            print(f"docs: {b.where()}: {'ok' if ok else 'FAILED'} ({time.time() - t0:.1f} s)")
            if not ok:
                failed += 1
                print("  " + script.replace("\n", "\n  "))
                print("  output:\n    " + out[-3000:].replace("\n", "\n    "))
    print(f"docs: {ran} blocks ran, {skipped} skipped")
    print(f"{max(0, ran + skipped - failed)} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
