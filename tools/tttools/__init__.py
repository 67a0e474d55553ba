"""What the tools share (tools/__init__.py says how tools are run):

  host    the host program: found by one rule (--host PATH, else $TT_HOST, else
          build/host/host of this checkout), run with its --stats read back
  cli     the argparse parent every tool that runs the host takes (--host)
"""
