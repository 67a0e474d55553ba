"""tunetrace's tools: measurements, figures, data sets and checks around the host program.

tools/ is one Python package. Every tool is a module run from the repository root with

    /usr/bin/python3 -m tools.TOPIC.NAME [options]      # e.g. -m tools.tuning.analyze --help

or from any folder with CHECKOUT/tools/run TOPIC.NAME [options] (what the shell scripts use).
What several tools need is in tools.tttools: the host program found by one rule and run one
way (host), the command-line options every tool shares (cli) and the tuning database read
through the library (db); images and the one rRMSE
are in tools.common.images. A tool imports them, and other tools' functions, by name
(`from tools.tttools import host`), never by editing sys.path.
"""
