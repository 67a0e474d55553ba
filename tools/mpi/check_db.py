"""Checks a tuning database merged by tunetrace-mpi against its job list (issue 18), and
optionally against the database of another run of the same list (e.g. `mpirun -np 1` against
`-np 2`):

  /usr/bin/python3 -m tools.mpi.check_db --jobs jobs.json --db np2.db [--against np1.db]

Against the job list (0 rows lost or duplicated):
  * every job of the list is merged (its tag in the table `merges`, asked of
    `tunetrace-mpi --list`), and no tag outside the list is;
  * the rows are exactly those of the jobs: count(samples) = the sum of the merged rows,
    and the rows of each job (one host run: one run_id) are as many as its merge copied;
  * no row twice: no two rows equal in every column but their id.
Against another database of the same list: the same tags with the same row counts, and
per job the same rows in everything but timings: scene, camera, context, indicators,
plugin and version, objective, status, mode, iteration, tuner, and the configurations.
The configurations an exploration measures follow from its seed, so they must be equal;
those of a Nelder-Mead search follow the measured costs after the first simplex, so where
they differ it is reported (how many, from which iteration) and is not a failure unless
--strict. Timings, ids, run ids, machine, host, rank, timestamps are never compared.
Frame ranges carry no rows and are left out of the comparison (their tags name their
folder; mpi/tests/mpi_driver.sh compares their pixels). Exit 0: all
checks hold; 1: a check failed (each printed); 2: bad arguments or unreadable files.
"""
import collections
import json
import os
import subprocess
import sys

from tools.tttools import cli, host
from tools.tttools import db as tunedb
# everything but timings and where/when a row was measured
KEY = ("scene_id", "camera", "context", "indicators", "plugin", "plugin_version", "objective",
       "status", "mode", "iteration", "tuner")


def tags_of_list(driver, jobs, db):
    """{tag: done} of the job list, as tunetrace-mpi --list prints it (one process)."""
    p = subprocess.run([driver, "--jobs", jobs, "--db", db, "--list"], capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"check_db: {driver} --list failed:\n{p.stderr[-2000:]}")
    out = {}
    for line in p.stdout.splitlines():
        state, _, tag = line.partition(" ")
        out[tag] = state == "done"
    return out


def load(db):
    if not os.path.exists(db):
        print(f"check_db: {db}: no such file", file=sys.stderr)
        sys.exit(2)
    merges = {m["tag"]: m for m in tunedb.merges(db)}
    rows = tunedb.samples(db)
    return merges, list(rows[0]) if rows else [], rows


def check(a):
    problems = []
    driver = a.driver
    listed = tags_of_list(driver, a.jobs, a.db)
    merges, cols, rows = load(a.db)
    todo = [t for t, done in listed.items() if not done]
    extra = [t for t in merges if t not in listed]
    if todo:
        problems.append(f"{len(todo)} of {len(listed)} jobs not merged, e.g. {todo[0]}")
    if extra:
        problems.append(f"{len(extra)} merged tags are not jobs of {a.jobs}, e.g. {extra[0]}")
    total = sum(m["rows"] for m in merges.values())
    if total != len(rows):
        problems.append(f"{len(rows)} rows in samples, but the merges copied {total}: "
                        f"{len(rows) - total:+d} rows outside the jobs")
    # one host run per job: the runs' sizes are the merges' row counts
    by_run = collections.Counter(r["run_id"] for r in rows)
    with_rows = sorted(m["rows"] for m in merges.values() if m["rows"] > 0)
    if sorted(by_run.values()) != with_rows:
        problems.append(f"rows per host run {sorted(by_run.values())} differ from rows per "
                        f"merged job {with_rows}")
    skip = {"id"}
    seen = collections.Counter(tuple(text(r[c]) for c in cols if c not in skip) for r in rows)
    dup = sum(n - 1 for n in seen.values() if n > 1)
    if dup:
        problems.append(f"{dup} rows are in the database twice")
    kinds = collections.Counter(json.loads(m["note"])["job"]["kind"] for m in merges.values())
    print(f"{a.db}: {len(merges)} of {len(listed)} jobs merged "
          f"({', '.join(f'{n} {k}' for k, n in sorted(kinds.items()))}), {len(rows)} rows, "
          f"{max(0, len(listed) - len(merges) + len(extra))} jobs lost, {dup} rows duplicated, "
          f"{len(rows) - total:+d} rows outside the jobs")
    if a.against:
        problems += compare(a, merges, rows)
    for p in problems:
        print("FAIL: " + p)
    return 1 if problems else 0


def text(v):
    """A row's value as comparable text (the parsed JSON fields with their keys sorted)."""
    return json.dumps(v, sort_keys=True) if isinstance(v, (dict, list)) else str(v)


def signature(rows):
    """A job's rows without timings: sorted (iteration, key..., config)."""
    return sorted(tuple([r["iteration"] if r["iteration"] is not None else -1] +
                        [text(r[k]) for k in KEY] + [text(r["config"])]) for r in rows)


def per_job(merges, rows):
    """{tag: rows}: each merged job's rows, by its host run (the run whose camera, objective
    and mode match the job, and whose size is the merge's count)."""
    runs = collections.defaultdict(list)
    for r in rows:
        runs[r["run_id"]].append(r)
    out = {}
    free = dict(runs)
    for tag, m in merges.items():
        job = json.loads(m["note"])["job"]
        if job["kind"] == "frames" or m["rows"] == 0:
            out[tag] = []
            continue
        mode = "explore" if job["kind"] == "explore" else "tune"
        for run, rs in list(free.items()):
            if len(rs) == m["rows"] and any(r["mode"] == mode for r in rs) and \
               job["camera"] in {tunedb.path_index(r) for r in rs} and \
               (job.get("objective") is None or job["objective"] in {r["objective"] for r in rs}):
                out[tag] = rs
                del free[run]
                break
    return out


def compare(a, merges, rows):
    problems = []
    merges2, _, rows2 = load(a.against)
    # frame ranges carry no rows, and their tags name their folder: compared by pixels elsewhere
    rowful = lambda ms: {t: m for t, m in ms.items() if json.loads(m["note"])["job"]["kind"] != "frames"}
    merges, merges2 = rowful(merges), rowful(merges2)
    if set(merges) != set(merges2):
        only = sorted(set(merges) ^ set(merges2))
        return [f"{a.db} and {a.against} merged different jobs ({len(only)}), e.g. {only[0]}"]
    j1, j2 = per_job(merges, rows), per_job(merges2, rows2)
    differ = collections.Counter()
    first_diff = {}
    for tag in sorted(merges):
        if merges[tag]["rows"] != merges2[tag]["rows"]:
            problems.append(f"{tag}: {merges[tag]['rows']} rows in {a.db}, {merges2[tag]['rows']} in {a.against}")
            continue
        if tag not in j1 or tag not in j2:
            problems.append(f"{tag}: its rows are not found as one host run")
            continue
        s1, s2 = signature(j1[tag]), signature(j2[tag])
        if [x[:-1] for x in s1] != [x[:-1] for x in s2]:
            problems.append(f"{tag}: rows differ in more than timings")
            continue
        kind = json.loads(merges[tag]["note"])["job"]["kind"]
        bad = [x[0] for x, y in zip(s1, s2) if x[-1] != y[-1]]
        if bad:
            if kind != "tune" or a.strict:
                problems.append(f"{tag}: {len(bad)} configurations differ (from iteration {min(bad)})")
            differ[kind] += 1
            first_diff[tag] = min(bad)
    n = len(merges)
    tune = sum(1 for m in merges.values() if json.loads(m["note"])["job"]["kind"] == "tune")
    print(f"against {a.against}: {n} jobs, the same rows in everything but timings"
          + (f"; {differ['tune']} of {tune} searches took another path after iteration "
             f"{min(first_diff.values())} (steered by the measured costs)" if differ["tune"] else
             f"; every search took the same path"))
    return problems


def main():
    ap = cli.parser(__doc__)
    ap.add_argument("--jobs", required=True, help="the job list the run(s) ran")
    ap.add_argument("--db", required=True, help="the merged database")
    ap.add_argument("--against", help="another run's merged database of the same list")
    ap.add_argument("--strict", action="store_true", help="searches must take the same path too")
    ap.add_argument("--driver", help="tunetrace-mpi (default: the one of the host's build)")
    a = ap.parse_args()
    try:
        a.driver = a.driver or host.build_path(host.find(a.host), "mpi", "tunetrace-mpi")
    except host.HostError as e:
        print(f"check_db: {e}", file=sys.stderr)
        return 2
    if not os.access(a.driver, os.X_OK):
        print(f"check_db: {a.driver}: not built (tunetrace-mpi needs Open MPI)", file=sys.stderr)
        return 2
    return check(a)


if __name__ == "__main__":
    sys.exit(main())
