"""Regenerates the figures the docs show and writes the results page.

  /usr/bin/python3 -m tools.evidence.run --quick            # minutes: docs/results/index.html
  /usr/bin/python3 -m tools.evidence.run --quick --out DIR  # the page and its PNGs in DIR
  /usr/bin/python3 -m tools.evidence.run --full             # prints the full-settings commands
  /usr/bin/python3 -m tools.evidence.run --full --page-only # rebuilds the page only

--quick runs every figure tool the docs rely on (tools/evidence/steps.py): the ones whose
figures come from committed data (hybrid tuning's Figs. 3.16-3.21, the accel render split)
redraw those figures into OUT; the ones that measure (tuning analysis, cylinder sweep,
Theta histogram, PSSMLT tuning, integrator error against time) run at toy sizes into
OUT/quick. Then the page (tools/evidence/page.py) is written: per thesis chapter our figure
and numbers beside the thesis', the command, the outcome. Exit 1 when a step failed (the
page is still written and names the failure).

--full measures nothing by itself: the committed figures took hours each on the project's
2-core machine, so it prints each figure's full-settings command (the ones the page shows;
OUT/full_commands.txt) to run by hand, then rebuilds the page from what is committed.
The quick pass needs the build (bootstrap) and python3-matplotlib, -numpy, -scipy,
-openimageio; the browser check of the page is tools/evidence/check_page.py."""
import json
import os
import shutil
import sys
import tempfile

from tools.evidence import entries, page, steps
from tools.tttools import cli
from tools.tttools import host as tthost


def _write(path, text):
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(text)
    os.replace(tmp, path)


def main(argv=None):
    ap = cli.parser(__doc__)
    g = ap.add_mutually_exclusive_group(required=True)
    g.add_argument("--quick", action="store_true", help="run the figure tools at quick settings")
    g.add_argument("--full", action="store_true", help="print the full-settings commands")
    ap.add_argument("--out", default=os.path.join(tthost.ROOT, "docs", "results"),
                    help="folder of index.html and the PNGs (default docs/results)")
    ap.add_argument("--page-only", action="store_true", help="only rebuild the page")
    ap.add_argument("--only", default=None, help="comma-separated quick steps (default: all)")
    ap.add_argument("--keep-work", action="store_true", help="keep the scratch folder")
    a = ap.parse_args(argv)
    out = os.path.abspath(a.out)
    os.makedirs(out, exist_ok=True)
    names = [s.__name__ for s in steps.QUICK]
    only = a.only.split(",") if a.only else None
    for n in only or []:
        if n not in names:
            ap.error(f"--only: unknown step {n!r} (steps: {', '.join(names)})")
    results = {}
    saved = os.path.join(out, "quick_pass.json")  # the last quick pass, for page-only builds
    text = "".join(f"# {en['thesis']}: {en['title']}\n{en['command']}\n\n" for en in entries.E)
    _write(os.path.join(out, "full_commands.txt"),
           "# The full-settings command of every figure on the results page (index.html),\n"
           "# run from the repository root; each takes minutes to hours on 2 cores.\n\n" + text)
    if a.full:
        print(text, end="")
    if a.full or a.page_only:
        try:
            with open(saved) as f:
                results = json.load(f)
        except (OSError, ValueError):
            results = {}
    else:
        try:
            host = tthost.find(a.host)
        except tthost.HostError as e:
            ap.exit(2, f"evidence: {e}\n")
        work = tempfile.mkdtemp(prefix="tt_evidence.")
        try:
            results = steps.run_quick(host, out, work, os.path.join(work, "log.txt"), only)
            failed = [n for n, r in results.items() if not r["ok"]]
            if failed and a.keep_work is False:
                print(f"evidence: log of the commands: {work}/log.txt (kept)", file=sys.stderr)
        finally:
            if not a.keep_work and not any(not r["ok"] for r in results.values()):
                shutil.rmtree(work, ignore_errors=True)
        _write(saved, json.dumps(results, indent=1) + "\n")
    path = page.build(out, results, "quick" if a.quick else "full")
    print(f"evidence: wrote {path}")
    return 1 if any(not r["ok"] for r in results.values()) else 0


if __name__ == "__main__":
    sys.exit(main())
