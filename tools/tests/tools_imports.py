"""tools/ is one package whose every module imports with only the packages tools/bootstrap.sh
installs (run with tests/support/bootstrap_python first on PYTHONPATH, which blocks torch and
bpy), except the modules declared below as needing torch (training) or bpy (inside Blender):

  - each module imports by its name (importlib: tools.TOPIC.NAME), as `python3 -m` runs it;
  - each tool (a module with a __main__ block) answers `python3 -m tools.TOPIC.NAME --help`
    from another folder than the repository root with PYTHONPATH naming the checkout: a
    usage text, no traceback;
  - no module edits sys.path: a tool reaches another's functions by importing them;
  - one way to find the host: no module but tools/tttools/ builds a host path itself
    (BUILD/host/host) or takes a --build option (cli.HOST's --host, host.find);
  - one way to read the tuning database: no module but tools/tttools/db.py (and
    hybrid/baseline.py, for its own table hybrid_jobs) opens it with sqlite3."""
import importlib
import os
import re
import subprocess
import sys
import tempfile

NEEDS = {  # module (relative to tools/) -> the blocked package it needs (torch: only taa_train), and why
    "taa/dataset.py": "torch (training windows are torch tensors)",
    "taa/taa_model.py": "torch (the network)",
    "taa/train.py": "torch (training)",
    "taa/eval_torch.py": "torch (evaluates the PyTorch network)",
    "taa/export_golden.py": "torch (writes the PyTorch golden outputs)",
    "taa/ablations.py": "torch (trains the ablation networks)",
    "cycles/cycles_reference.py": "bpy (runs inside Blender)",
    "scenes/blender_skinned.py": "bpy (runs inside Blender)",
}
MAIN = re.compile(r"__name__\s*==\s*['\"]__main__['\"]")
SYS_PATH_EDIT = re.compile(r"sys\.path\s*(\.\s*(insert|append|extend)\s*\(|\[|\+?=)")
# a host path put together by hand, or a --build option: tools/tttools/host.py's job
HOST_BY_HAND = re.compile(r"""add_argument\(\s*['"]--build['"]|['"]host['"]\s*,\s*['"]host['"]\s*\)""")
HOST_FINDERS = ("tttools/",)
SQLITE = re.compile(r"^\s*(import sqlite3|from sqlite3 import)", re.M)
SQLITE_READERS = ("tttools/db.py", "hybrid/baseline.py")


def modules(root):
    """(relative path, module name) of every .py file under tools/ but tools/tests."""
    out = []
    for dirpath, dirs, names in os.walk(root):
        dirs[:] = sorted(d for d in dirs if d not in ("tests", "__pycache__"))
        for n in sorted(names):
            if n.endswith(".py"):
                rel = os.path.relpath(os.path.join(dirpath, n), root)
                name = "tools." + rel[:-3].replace(os.sep, ".")
                out.append((rel, name[:-len(".__init__")] if n == "__init__.py" else name))
    return out


def main():
    src = os.environ.get("TT_SOURCE_ROOT", ".")
    root = os.path.join(src, "tools")
    if sys.modules.get("torch", 0) is not None:
        print("FAIL: torch is not blocked (run through meson test: PYTHONPATH must start with "
              "tests/support/bootstrap_python)")
        return 1
    fail = checked = helped = 0
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [os.path.abspath(src)] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]))
    with tempfile.TemporaryDirectory() as elsewhere:
        for rel, name in modules(root):
            with open(os.path.join(root, rel)) as f:
                text = f.read()
            if SYS_PATH_EDIT.search(text):
                print(f"FAIL {rel}: edits sys.path (import the module by name instead)")
                fail += 1
            if HOST_BY_HAND.search(text) and not rel.startswith(HOST_FINDERS):
                print(f"FAIL {rel}: finds the host itself (use cli.parser's --host and host.find)")
                fail += 1
            if SQLITE.search(text) and rel not in SQLITE_READERS:
                print(f"FAIL {rel}: opens the tuning database with sqlite3 (read it with "
                      "tools.tttools.db)")
                fail += 1
            if rel in NEEDS:
                print(f"skip {rel}: needs {NEEDS[rel]}")
                continue
            checked += 1
            try:
                importlib.import_module(name)
            except SystemExit:
                print(f"ok   {rel} (exits at import)")
                continue
            except BaseException as e:  # noqa: BLE001 - report whatever the import raised
                print(f"FAIL {rel}: import {name}: {type(e).__name__}: {e}")
                fail += 1
                continue
            if not MAIN.search(text):
                print(f"ok   {rel}")
                continue
            r = subprocess.run([sys.executable, "-m", name, "--help"], cwd=elsewhere, env=env,
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                               timeout=120)
            if "Traceback" in r.stdout or r.returncode not in (0, 1, 2) or "usage" not in r.stdout.lower():
                print(f"FAIL {rel}: python3 -m {name} --help: exit {r.returncode}\n{r.stdout[-1500:]}")
                fail += 1
                continue
            helped += 1
            print(f"ok   {rel} (-m {name} --help)")
    tests = os.path.join(root, "tests")
    for n in sorted(os.listdir(tests)):
        if n.endswith(".py"):
            with open(os.path.join(tests, n)) as f:
                if SYS_PATH_EDIT.search(f.read()):
                    print(f"FAIL tests/{n}: edits sys.path (import the module by name instead)")
                    fail += 1
    print(f"{checked} modules imported, {helped} tools answered --help, {fail} failed")
    return 1 if fail or checked == 0 else 0


if __name__ == "__main__":
    sys.exit(main())
