#!/usr/bin/python3
"""What the Python API reads is refused at once when it cannot be read, and reading changes
nothing:

  - tunetrace.read_image of a FIFO, /dev/zero, /dev/urandom or a folder raises tunetrace.Error
    naming the file and what it is (it hung inside OpenImageIO); a hang fails the test after
    60 s (faulthandler's watchdog thread: a signal handler would never run while C blocks),
    the traceback naming the call;
  - TuningDB(path) opens read-only: the file keeps its bytes (no WAL switch, no tables added),
    another program's SQLite file is refused by name and left as it was, a database opened
    read-only cannot be tuned into, and TuningDB(path, write=True) creates one.

Environment: TT_BUILD_ROOT (tests/meson.build)."""
import faulthandler
import os
import sqlite3
import sys
import tempfile

BUILD = os.environ["TT_BUILD_ROOT"]
sys.path.insert(0, os.path.join(BUILD, "python"))

import tunetrace as tt  # noqa: E402

failures = 0
checks = 0
step = "start"


def check(cond, what):
    global failures, checks
    checks += 1
    if not cond:
        failures += 1
        print(f"FAIL: {what}", file=sys.stderr)


def raises(fn, *needles):
    try:
        fn()
    except tt.Error as e:
        check(all(n in str(e) for n in needles), f"{step}: message {e!r} lacks {needles}")
        return
    check(False, f"{step}: no error raised")


def watch(what):
    """Fails the test (exit 1, tracebacks) if `what` has not returned in 60 s."""
    global step
    step = what
    print(f"python_inputs: {what}", file=sys.stderr, flush=True)
    faulthandler.dump_traceback_later(60, exit=True)


with tempfile.TemporaryDirectory() as d:
    fifo = os.path.join(d, "reference.exr")
    os.mkfifo(fifo)
    for path, kind in ((fifo, "a FIFO"), ("/dev/zero", "a character device"),
                       ("/dev/urandom", "a character device"), (d, "a directory")):
        watch(f"read_image({path}) must not hang")
        raises(lambda: tt.read_image(path), path, kind)
        faulthandler.cancel_dump_traceback_later()

    # another program's SQLite file: refused, unchanged
    foreign = os.path.join(d, "photos.db")
    con = sqlite3.connect(foreign)
    con.execute("CREATE TABLE photos (id INTEGER, name TEXT)")
    con.execute("INSERT INTO photos VALUES (1, 'x')")
    con.commit()
    con.close()
    before = open(foreign, "rb").read()
    step = "TuningDB(foreign)"
    raises(lambda: tt.TuningDB(foreign), foreign, "not a tunetrace tuning database", "photos")
    step = "TuningDB(foreign, write=True)"
    raises(lambda: tt.TuningDB(foreign, write=True), foreign, "not a tunetrace tuning database")
    check(open(foreign, "rb").read() == before, "the foreign file was changed")
    watch("TuningDB(FIFO) must not hang")
    raises(lambda: tt.TuningDB(fifo), fifo, "a FIFO")
    faulthandler.cancel_dump_traceback_later()
    step = "TuningDB(missing)"
    raises(lambda: tt.TuningDB(os.path.join(d, "missing.db")), "missing.db")

    # a database: created for writing, then read without a byte changing
    path = os.path.join(d, "tuning.db")
    with tt.TuningDB(path, write=True) as db:
        check(not db.read_only and db.count() == 0, "write=True opens for writing")
    before = open(path, "rb").read()
    with tt.TuningDB(path) as db:
        check(db.read_only and db.count() == 0 and db.rows() == [] and db.bad_rows == 0,
              "TuningDB(path) reads")
        db.export_csv(os.path.join(d, "rows.csv"))
        step = "export_csv onto the database"
        raises(lambda: db.export_csv(path), "would replace the tuning database")
    check(open(path, "rb").read() == before, "a read-only TuningDB changed the file")

print(f"python_inputs: {checks} checks, {failures} failed")
sys.exit(1 if failures else 0)
