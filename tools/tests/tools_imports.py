#!/usr/bin/python3
"""Every Python tool under tools/ imports with only the packages tools/bootstrap.sh installs
(run with tests/support/bootstrap_python first on PYTHONPATH, which blocks torch and bpy),
except the tools declared below as needing torch (training) or bpy (inside Blender).
A tool's module-level code runs (run_name is not "__main__", so main() does not)."""
import os
import runpy
import sys

NEEDS = {  # tool (relative to tools/) -> the non-bootstrap package it needs, and why
    "taa/dataset.py": "torch (training windows are torch tensors)",
    "taa/taa_model.py": "torch (the network)",
    "taa/train.py": "torch (training)",
    "taa/eval_torch.py": "torch (evaluates the PyTorch network)",
    "taa/export_golden.py": "torch (writes the PyTorch golden outputs)",
    "taa/ablations.py": "torch (trains the ablation networks)",
    "cycles/cycles_reference.py": "bpy (runs inside Blender)",
}


def main():
    root = os.path.join(os.environ.get("TT_SOURCE_ROOT", "."), "tools")
    if sys.modules.get("torch", 0) is not None:
        print("FAIL: torch is not blocked (run through meson test: PYTHONPATH must start with "
              "tests/support/bootstrap_python)")
        return 1
    fail = checked = 0
    for dirpath, dirs, names in sorted(os.walk(root)):
        dirs[:] = [d for d in dirs if d != "tests"]  # tools/tests holds tests, not tools
        for n in sorted(names):
            if not n.endswith(".py"):
                continue
            path = os.path.join(dirpath, n)
            rel = os.path.relpath(path, root)
            if rel in NEEDS:
                print(f"skip {rel}: needs {NEEDS[rel]}")
                continue
            saved = list(sys.path)
            sys.path.insert(0, dirpath)
            try:
                runpy.run_path(path, run_name="__tt_import_check__")
                print(f"ok   {rel}")
            except SystemExit:
                print(f"ok   {rel} (exits at import)")
            except BaseException as e:  # noqa: BLE001 - report whatever the import raised
                print(f"FAIL {rel}: {type(e).__name__}: {e}")
                fail += 1
            finally:
                sys.path[:] = saved
            checked += 1
    print(f"{checked} tools imported, {fail} failed")
    return 1 if fail or checked == 0 else 0


if __name__ == "__main__":
    sys.exit(main())
