"""What the tools share (tools/__init__.py says how tools are run):

  host    the host program: found by one rule (--host PATH, else $TT_HOST, else
          build/host/host of this checkout), run with its --stats read back (run; render
          for one measured render: stats and CPU seconds)
  cli     the argparse parent every tool that runs the host takes (--host)
  db      the tuning database, read through the library's Python binding
          (tunetrace.TuningDB), and the few things the library does not do (merges, a
          filtered copy, the schema version): the one place tools open it with sqlite3
"""
