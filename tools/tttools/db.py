"""The tuning database, read one way by every tool.

The library owns the database's schema (core/src/tuning/tunedb.c); tools read its rows
through the library, with the Python binding's `tunetrace.TuningDB` (tt_tunedb_foreach), so
a tool never spells a column of the samples table in SQL:

  samples(path, plugin=None)   every row as a dict (the binding's rows(): camera, context,
                               config and metrics parsed, indicators a list or None, status
                               "ok" / "infeasible" / "failed")
  ok(row)                      the row is a measurement (status ok)
  path_index(row)              the camera's --camera-index on a path, else None

Which binding: the package of a build tree (BUILD/python/tunetrace beside the host that
tttools/host.py finds without --host: $TT_HOST, else build/host/host of this checkout),
loaded from its folder by file location (no sys.path edit); else an installed `tunetrace`
(meson install, pip install ./python). Nothing to set up for a tool in a built checkout or
in the suite (which sets $TT_HOST).

What the library does not read or write is here too, the one place in tools/ that opens
the file with sqlite3: the schema version (PRAGMA user_version), the `merges` table that
tt_tunedb_merge fills (its notes), a copy of some rows into a new database (copy_samples: a
warm start or a training set; the rows are chosen on the binding's dicts and copied as
stored, byte for byte, since the library's lookups compare camera and context as text),
deleting and re-labelling a scene's rows (tools/hybrid/baseline.py's --restore), counting
rows and SQLite's integrity check. A tool's own table in the file (baseline.py's
hybrid_jobs) is that tool's.
"""
import contextlib
import importlib.util
import os
import sqlite3
import sys

from tools.tttools import host

_LIB = None
_ROWS = {}  # (path, plugin) -> (the file's size and mtime, rows): a tool reads a file once

SQLiteError = sqlite3.Error
"""What row_ids, integrity and count raise when SQLite cannot read the file."""


class DBError(SystemExit):
    """The binding cannot be loaded or a database cannot be read; str() is the message."""

    def __str__(self):
        return str(self.code)


def _build_package():
    """BUILD/python/tunetrace of the host's build tree, or None."""
    try:
        build = host.build_dir(host.find())
    except host.HostError:
        return None
    pkg = os.path.join(build, "python", "tunetrace") if build else None
    return pkg if pkg and os.path.exists(os.path.join(pkg, "__init__.py")) else None


def library():
    """The tunetrace module (the host's build tree's package, else an installed one)."""
    global _LIB
    if _LIB is not None:
        return _LIB
    pkg = _build_package()
    if pkg and "tunetrace" not in sys.modules:
        spec = importlib.util.spec_from_file_location(
            "tunetrace", os.path.join(pkg, "__init__.py"), submodule_search_locations=[pkg])
        mod = importlib.util.module_from_spec(spec)
        sys.modules["tunetrace"] = mod  # its own imports (from . import _lib) find it
        try:
            spec.loader.exec_module(mod)
        except Exception:
            del sys.modules["tunetrace"]
            raise
        _LIB = mod
        return _LIB
    try:
        import tunetrace
    except ImportError as e:
        raise DBError("tools read the tuning database through the library's Python binding "
                      f"(tunetrace), which is not built or installed ({e}): build it (ninja -C "
                      "build), name a build with --host BUILD/host/host or $TT_HOST, or "
                      "install it (meson install -C build, pip install ./python)") from None
    _LIB = tunetrace
    return _LIB


def samples(path, plugin=None):
    """Every row of the database at `path` (of `plugin`, or all) in insertion order, read by
    the library; DBError naming the file if it does not exist or is not a tuning database.
    Read once while the file is unchanged: the rows are shared, not to be modified."""
    tt = library()
    if not os.path.exists(path):
        raise DBError(f"{path}: no such tuning database")
    st = os.stat(path)
    sig = (st.st_size, st.st_mtime_ns)
    key = (os.path.abspath(path), plugin)
    if key in _ROWS and _ROWS[key][0] == sig:
        return _ROWS[key][1]
    try:
        with tt.TuningDB(path) as db:
            rows = db.rows(plugin)
    except tt.Error as e:
        raise DBError(f"{path}: {e}") from None
    _ROWS[key] = (sig, rows)
    return rows


def ok(row):
    """The row is a finished measurement (status ok; infeasible and failed rows have no cost)."""
    return row["status"] == "ok"


def path_index(row):
    """The --camera-index of the row's camera on a camera path, else None."""
    cam = row.get("camera")
    return cam.get("path_index") if isinstance(cam, dict) else None


def indicators(row):
    """The row's scene indicators by name (as host --states takes them), or None."""
    v = row.get("indicators")
    return dict(zip(library().INDICATORS, v)) if v is not None else None


# ------------------------------------------------------------------ what the library lacks


def _connect(path, write=False):
    if not os.path.exists(path):
        raise DBError(f"{path}: no such tuning database")
    if write:
        return sqlite3.connect(path, timeout=60)
    return sqlite3.connect(f"file:{path}?mode=ro", uri=True, timeout=60)


@contextlib.contextmanager
def _opened(path_or_con):
    """A connection: the caller's open one as it is, or the path's (read-only, closed after)."""
    if isinstance(path_or_con, sqlite3.Connection):
        yield path_or_con
        return
    con = _connect(path_or_con)
    try:
        yield con
    finally:
        con.close()


def schema_version(path_or_con):
    """The library's schema version of the file (PRAGMA user_version; 0: not a tuning
    database yet)."""
    with _opened(path_or_con) as con:
        return con.execute("PRAGMA user_version").fetchone()[0]


def merges(path_or_con):
    """The tags merged into the database (tt_tunedb_merge) as dicts: tag, rows, source, note
    (text; a job's JSON for tunetrace-mpi), timestamp; [] where nothing was ever merged."""
    with _opened(path_or_con) as con:
        if not con.execute("SELECT count(*) FROM sqlite_master WHERE name = 'merges'").fetchone()[0]:
            return []
        cur = con.execute("SELECT tag, rows, source, note, timestamp FROM merges")
        names = [d[0] for d in cur.description]
        return [dict(zip(names, r)) for r in cur]


def count(path_or_con):
    """Rows in the samples table (through SQLite: also for a file being restored)."""
    with _opened(path_or_con) as con:
        return con.execute("SELECT count(*) FROM samples").fetchone()[0]


def row_ids(path):
    """The ids of every row (through SQLite, read-only, waiting up to 60 s for a writer):
    what a crash test compares before and after."""
    with _opened(path) as con:
        return {r[0] for r in con.execute("SELECT id FROM samples")}


def integrity(path):
    """SQLite's integrity check of the file: "ok" or what is broken."""
    con = _connect(path, write=True)
    try:
        return con.execute("PRAGMA integrity_check").fetchone()[0]
    finally:
        con.close()


def drop_scenes(con, scene_ids):
    """Deletes every row of these scene ids (an open connection: part of the caller's
    transaction)."""
    con.executemany("DELETE FROM samples WHERE scene_id = ?", [(x,) for x in scene_ids])


def relabel_scene(con, old, new):
    """Gives the rows of scene id `old` the id `new` (an open connection)."""
    con.execute("UPDATE samples SET scene_id = ? WHERE scene_id = ?", (new, old))


def copy_samples(src_path, path, keep):
    """A tuning database at `path` holding the rows of `src_path` for which keep(row) is true
    (row: a dict of samples()), copied as stored, with the source's schema and version; made
    atomically, and kept as it is if `path` exists (a tool's cache). Returns `path`."""
    if os.path.exists(path):
        return path
    ids = [r["id"] for r in samples(src_path) if keep(r)]
    tmp = path + ".tmp"
    if os.path.exists(tmp):
        os.remove(tmp)
    src = _connect(src_path)
    dst = sqlite3.connect(tmp)
    try:
        dst.execute(src.execute("SELECT sql FROM sqlite_master WHERE name = 'samples'").fetchone()[0])
        dst.execute(f"PRAGMA user_version = {int(schema_version(src))}")
        cols = ",".join(r[1] for r in src.execute("PRAGMA table_info(samples)"))
        marks = ",".join("?" * len(cols.split(",")))
        for k in range(0, len(ids), 500):
            part = ids[k:k + 500]
            got = src.execute(f"SELECT {cols} FROM samples WHERE id IN ({','.join('?' * len(part))})",
                              part).fetchall()
            dst.executemany(f"INSERT INTO samples ({cols}) VALUES ({marks})", got)
        dst.commit()
    finally:
        dst.close()
        src.close()
    os.replace(tmp, path)
    return path
