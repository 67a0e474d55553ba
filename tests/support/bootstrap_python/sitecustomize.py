"""Put first on PYTHONPATH by tests/meson.build: every Python tool the suite runs sees only
the packages tools/bootstrap.sh installs, even on a machine where more were installed by hand
(CI runs on such a machine; a fresh one has only bootstrap's). Importing a blocked module
raises ImportError naming it, so a tool that needs one fails its test everywhere, not only on
fresh machines. Training needs torch and the Cycles reference needs Blender's bpy: those tools
are not run by the suite (tools/tests/tools_imports.py checks every other tool imports without them).
"""
import sys

# Modules of packages that bootstrap deliberately does not install (see README, Dependencies).
NOT_INSTALLED_BY_BOOTSTRAP = ("torch", "torchvision", "bpy")

for _name in NOT_INSTALLED_BY_BOOTSTRAP:
    sys.modules[_name] = None  # `import torch` -> ImportError ("import of torch halted")
