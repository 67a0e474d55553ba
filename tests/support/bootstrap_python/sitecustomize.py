"""Put first on PYTHONPATH by tests/meson.build: every Python tool the suite runs sees only
the packages tools/bootstrap.sh installs, even on a machine where more were installed by hand
(CI runs on such a machine; a fresh one has only bootstrap's). Importing a blocked module
raises ImportError naming it, so a tool that needs one fails its test everywhere, not only on
fresh machines. The Cycles reference needs Blender's bpy, which bootstrap does not install:
it is always blocked. Training needs torch (python3-torch, installed by bootstrap): it is
blocked too, so that the evaluation tools stay torch-free (tools/tests/tools_imports.py
checks every other tool imports without it), except in the one test that runs training
(tools/tests/taa_train.sh), which sets TT_TEST_ALLOW_TORCH=1.
"""
import os
import sys

# Modules of packages that bootstrap deliberately does not install (see README, Dependencies).
NOT_INSTALLED_BY_BOOTSTRAP = ("bpy",)
# Installed, but only the training test may use them.
TRAINING_ONLY = ("torch", "torchvision")

_blocked = NOT_INSTALLED_BY_BOOTSTRAP
if os.environ.get("TT_TEST_ALLOW_TORCH") != "1":
    _blocked += TRAINING_ONLY
for _name in _blocked:
    sys.modules[_name] = None  # `import torch` -> ImportError ("import of torch halted")
