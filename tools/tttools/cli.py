"""The command line every tool shares.

HOST is the argparse parent of every tool that runs the host program: it adds the one
`--host PATH` option (tttools/host.py says how the host is found without it).
parser(doc) makes a tool's parser: its module docstring as the description (kept as
written: the docstrings show commands) and HOST as a parent unless host=False.
"""
import argparse

HOST = argparse.ArgumentParser(add_help=False)
HOST.add_argument("--host", metavar="PATH",
                  help="the host program to run (default: $TT_HOST, else build/host/host of this "
                       "checkout; tools that need more of a build take it from the host's)")


def parser(doc, host=True, **kw):
    """A tool's ArgumentParser: `doc` as the description (raw: line breaks kept) and the
    --host option of HOST unless host=False."""
    kw.setdefault("formatter_class", argparse.RawDescriptionHelpFormatter)
    return argparse.ArgumentParser(description=doc, parents=[HOST] if host else [], **kw)
