#!/usr/bin/python3
"""Concurrency of the tuning database (#13): several host processes tune into one --db at
the same moment, starting on a file that does not exist yet (so they race to create the
schema and switch it to WAL), three rounds. Every process must exit 0 without a "database is
locked" or "busy" message, record every measurement it made (its rows, told apart by the
process id that ends run_id, equal its --stats tuning.measured; db_unrecorded 0), and the
file must pass PRAGMA integrity_check."""
import json
import os
import sqlite3
import subprocess
import sys
import tempfile

PROCESSES = 3
ROUNDS = 3
ITERATIONS = 12


def main():
    build = os.environ.get("TT_BUILD_ROOT", "build")
    source = os.environ.get("TT_SOURCE_ROOT", ".")
    host = os.path.join(build, "host", "host")
    scene = os.path.join(source, "scenes", "cornell-box", "scene.json")
    failures = []
    with tempfile.TemporaryDirectory(prefix="tt_tune_concurrency_") as tmp:
        db = os.path.join(tmp, "shared", "tuning.db")  # the folder does not exist either
        for rnd in range(ROUNDS):
            procs = []
            for k in range(PROCESSES):
                stats = os.path.join(tmp, "r%d_p%d.json" % (rnd, k))
                args = [host, "--quiet", "--plugin", "tuner_nm", "--iterations", str(ITERATIONS),
                        "--spp", "1", "--res", "8x8", "--seed", str(100 * rnd + k + 1),
                        "--db", db, "--stats", stats,
                        "--out", os.path.join(tmp, "r%d_p%d.exr" % (rnd, k)), scene]
                procs.append((subprocess.Popen(args, stdout=subprocess.PIPE,
                                               stderr=subprocess.STDOUT, text=True), stats))
            for p, stats in procs:
                out, _ = p.communicate(timeout=600)
                if p.returncode != 0:
                    failures.append("round %d pid %d: exit %d: %s" % (rnd, p.pid, p.returncode,
                                                                      out[-2000:]))
                for word in ("locked", "busy", "BUSY"):
                    if word in out:
                        failures.append("round %d pid %d: \"%s\" in its output: %s"
                                        % (rnd, p.pid, word, out[-2000:]))
                try:
                    with open(stats) as f:
                        tuning = json.load(f)["tuning"]
                except (OSError, ValueError, KeyError) as e:
                    failures.append("round %d pid %d: no --stats tuning record: %s" % (rnd, p.pid, e))
                    continue
                con = sqlite3.connect(db)
                rows = con.execute("SELECT count(*) FROM samples WHERE run_id LIKE ?",
                                   ("%%-%d" % p.pid,)).fetchone()[0]
                con.close()
                if rows != tuning["measured"] or tuning.get("db_unrecorded", 0) != 0:
                    failures.append("round %d pid %d: %d rows in the database, %d measured, %s "
                                    "unrecorded" % (rnd, p.pid, rows, tuning["measured"],
                                                    tuning.get("db_unrecorded")))
                print("round %d pid %d: %d measured, %d from the database, %d rows"
                      % (rnd, p.pid, tuning["measured"], tuning["cached"], rows))
            con = sqlite3.connect(db)
            check = con.execute("PRAGMA integrity_check").fetchone()[0]
            total = con.execute("SELECT count(*) FROM samples").fetchone()[0]
            con.close()
            print("round %d: integrity_check %s, %d rows in all" % (rnd, check, total))
            if check != "ok":
                failures.append("round %d: integrity_check: %s" % (rnd, check))
    for f in failures:
        print("FAIL: " + f)
    print("tune_concurrency: %d processes x %d rounds, %d failures"
          % (PROCESSES, ROUNDS, len(failures)))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
