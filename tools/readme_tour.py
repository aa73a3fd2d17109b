#!/usr/bin/env python3
"""Run the README's command lines as written, and check they leave the checkout untouched.

    python3 tools/readme_tour.py [--python PYTHON] [--only sh|python]

From the checkout's root (``.ci/run`` calls it after the Python package is installed):

* the ``sh`` block of "A quick tour" runs in bash (``set -euo pipefail``), line after line,
  each line echoed first, so a failure names its line;
* every ``python`` block runs in PYTHON (default: this interpreter) from the checkout's root;
  a line ``print(...)  # Paths(...)`` must print exactly its comment;
* before and after, ``git status --porcelain --untracked-files=all --ignored`` must be the same
  (``target/`` excepted, where cargo builds): the tour writes only into its temporary folder.

Of the first screen's two commands the demo runs here too; ``.ci/run`` runs the test command
itself. The ``pip install`` block is what ``.ci/run`` does to build the package into its venv.
"""

import argparse
import re
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
# A README line must end by itself: the tour's shell block (about 4 minutes in CI, most of it
# `hls synth`) and each Python block stop with a failure beyond these.
SH_TIMEOUT_S = 1200
PY_TIMEOUT_S = 600


def blocks(text, lang):
    """(heading, body) of every fenced block of `lang`, with the `##` (or `###`) heading above
    it."""
    heading, out = "", []
    for m in re.finditer(r"^(###? [^\n]*)$|^```" + lang + r"\n(.*?)^```$", text, re.M | re.S):
        if m.group(1):
            heading = m.group(1)
        else:
            out.append((heading, m.group(2)))
    return out


def checkout_state():
    """What git sees in the checkout, outside target/."""
    out = subprocess.run(
        ["git", "status", "--porcelain", "--untracked-files=all", "--ignored"],
        cwd=ROOT, check=True, capture_output=True, text=True,
    ).stdout
    return sorted(line for line in out.splitlines() if not line[3:].startswith("target/"))


def run_sh(body):
    """The tour's shell lines, each echoed before it runs."""
    script = ["set -euo pipefail"]
    for line in body.splitlines():
        if line.strip():
            script.append(f"printf '%s\\n' {shell_quote('+ ' + line)} >&2")
        script.append(line)
    try:
        return subprocess.run(["bash", "-c", "\n".join(script)], cwd=ROOT, timeout=SH_TIMEOUT_S).returncode
    except subprocess.TimeoutExpired:
        print(f"the block ran over {SH_TIMEOUT_S} s: a line that never ends (a server?)", file=sys.stderr)
        return 1


def shell_quote(s):
    return "'" + s.replace("'", "'\\''") + "'"


def run_python(body, python):
    """One Python block; its `print(...)  # Paths(...)` lines must print their comments."""
    expected = re.findall(r"^print\(.*\)\s+#\s*(Paths\(.*?\))\s*$", body, re.M)
    try:
        done = subprocess.run(
            [python, "-c", body], cwd=ROOT, capture_output=True, text=True, timeout=PY_TIMEOUT_S
        )
    except subprocess.TimeoutExpired:
        return f"ran over {PY_TIMEOUT_S} s"
    sys.stdout.write(done.stdout)
    sys.stderr.write(done.stderr)
    if done.returncode != 0:
        return f"exit status {done.returncode}"
    printed = [line for line in done.stdout.splitlines() if line.startswith("Paths(")]
    if printed != expected:
        return f"printed {printed}, the README says {expected}"
    return None


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--python", default=sys.executable)
    parser.add_argument("--only", choices=["sh", "python"])
    args = parser.parse_args()
    text = (ROOT / "README.md").read_text()
    before = checkout_state()
    failures, start = [], time.monotonic()
    if args.only in (None, "sh"):
        first = blocks(text, "sh")[0][1]
        demo = "\n".join(l for l in first.splitlines() if not l.startswith("cargo test"))
        if run_sh(demo) != 0:
            failures.append("the first screen's demo failed")
        tours = [body for heading, body in blocks(text, "sh") if heading == "## A quick tour"]
        if len(tours) != 1:
            failures.append(f"expected one sh block under '## A quick tour', found {len(tours)}")
        for body in tours:
            if run_sh(body) != 0:
                failures.append("the quick tour stopped at the line echoed last")
    if args.only in (None, "python"):
        # The top README's Python blocks, then the API page's (python/README.md).
        for readme in (ROOT / "README.md", ROOT / "python" / "README.md"):
            name = readme.relative_to(ROOT)
            for k, (heading, body) in enumerate(blocks(readme.read_text(), "python")):
                print(f"+ {name}: python block {k + 1} ({heading})", file=sys.stderr)
                problem = run_python(body, args.python)
                if problem:
                    failures.append(f"{name}: python block {k + 1} under {heading!r}: {problem}")
    after = checkout_state()
    if after != before:
        changed = sorted(set(after) ^ set(before))
        failures.append(f"the tour changed the checkout: {changed}")
    print(f"readme tour: {time.monotonic() - start:.0f} s", file=sys.stderr)
    for f in failures:
        print(f"FAILED: {f}", file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
