"""Baseline data for hybrid autotuning (thesis 3.3.5.1): one Nelder-Mead search per
(scene, camera of the scene's path, objective), every measurement into one tuning DB.

A job is one search: `host --plugin tuner_nm --camera-index I --objective O --iterations N
--tune-spp 1 --clock cpu --threads 1 --db DB scene`. Every measurement is a DB row (scene id,
camera JSON with "path_index": I, context with spp/threads/clock/other plugins, indicators,
configuration, build/render ms, cost); the job itself is recorded in the table hybrid_jobs of
the same file when it finishes (its settings, the run's trajectory, CPU and wall seconds, the
load average). Jobs already in hybrid_jobs are skipped, so the command is resumable: kill it
and run it again. An interrupted search is not lost either: its measured rows are in the DB,
and the rerun's tuner (same seed) is answered from them until it reaches new configurations.

Costs are CPU time of the host process (--clock cpu) with one thread: on a shared machine the
wall time of a pass mostly measures who else ran (living-room, load 6-10: wall 380 ms vs
52 ms CPU per build); see tools/hybrid/README.md.

Jobs run in an order that keeps the finished set useful at any time: cameras by bit-reversed
rank (0, the middle, the quarters, ...), scenes and objectives interleaved within a camera.

  B="/usr/bin/python3 -m tools.hybrid.baseline"        # from the repository root
  $B --db /tmp/hybrid/baseline.db --work /tmp/hybrid/work    # all jobs
  $B --db DB --work W --list                        # jobs, one per line, done or not
  $B --db DB --work W --job bmw-m6:16:build+render  # one job (what an MPI rank runs)
  $B --db DB --work W --cameras 100 --iterations 80 # the thesis' full size
  $B --db DB --work W --shard 0/2 & $B --db DB --work W --shard 1/2  # 2 workers
  $B --db DB --work W --mpi 4            # the jobs on 4 MPI ranks (tunetrace-mpi)
  $B --db DB --work W --emit-jobs J.json # tunetrace-mpi's job list (srun/mpirun it)
  $B --db DB --work W --import-mpi       # jobs merged by tunetrace-mpi -> hybrid_jobs
  $B --db DB --work W --dump D.sql.xz    # the DB as a compressed SQL dump (for git)
  $B --db DB --work W --restore D.sql.xz # a new DB from it, scene files of this checkout

A dump keeps a baseline beyond the machine it ran on: --restore loads it into a new --db,
points hybrid_jobs.scene_file at this checkout's scenes (generating voxel and tessellated
into --work), checks that each scene's tt_scene_id is still the recorded one (host, 4x4),
and exits; then baseline.py with the same settings continues it and evaluate.py reads it.
A scene whose id changed is refused naming the parts that changed (hybrid_jobs.scene_parts:
geometry, materials, textures, lights); --remap-scenes keeps its rows with a warning.

With MPI (issue 18, mpi/README.md) every job runs the same host command on some rank and
tunetrace-mpi merges its rows into --db; the jobs it merged (table merges, their notes hold
the host's stats) become hybrid_jobs rows on import, which --mpi does when the run ends and
every run does at its start, so the two ways share one resumable job set.
"""
import json
import lzma
import os
import shutil
import sqlite3
import subprocess
import sys
import time

from tools.scenes import generate
from tools.tttools import cli, db, host

ROOT = host.ROOT
SHARED = os.path.abspath(os.path.join(ROOT, "..", "shared", "scenes"))

# name -> scene file (relative to the repository) or a generator command (tools/scenes).
SCENES = {
    "bmw-m6": "scenes/bmw-m6/scene.json",
    "living-room": "scenes/living-room/scene.json",
    "staircase": "scenes/staircase/scene.json",
    "bathroom": "scenes/bathroom/scene.json",
    "veach-ajar": "scenes/veach-ajar/scene.json",
    "killeroos": "scenes/killeroos/scene.json",
    "voxel": ("voxel", "scene.json"),           # vokselia stand-in, 1.27M triangles
    "tessellated": ("tessellated", "far.json"),  # buddha stand-in, 1.31M triangles
}
DEFAULT_SCENES = list(SCENES)
OBJECTIVES = ["render", "build+render"]
# The searched parameters: Table 3.1's eleven and our backend choice. `counters` (traversal
# statistics, a diagnostic that only slows rendering) is left at its default.
TUNE_PARAMS = ("quality,branchingFactor,maxDepth,sahBlockSize,minLeafSize,maxLeafSize,travcost,"
               "intcost,static,compact,robust,backend")

JOBS_SCHEMA = """CREATE TABLE IF NOT EXISTS hybrid_jobs (
  job TEXT PRIMARY KEY,       -- scene:path_index:objective:settings
  scene TEXT NOT NULL,        -- short name (SCENES)
  scene_file TEXT NOT NULL,   -- the file given to host
  scene_id TEXT,              -- tt_scene_id of the rows
  path_index INTEGER NOT NULL,-- --camera-index
  objective TEXT NOT NULL,
  iterations INTEGER NOT NULL,
  tune_spp INTEGER NOT NULL,
  resolution TEXT NOT NULL,
  threads INTEGER NOT NULL,
  clock TEXT NOT NULL,
  seed INTEGER NOT NULL,
  tuner TEXT NOT NULL,
  tune_params TEXT NOT NULL,
  default_cost REAL,
  best_cost REAL,
  best_config TEXT,
  converged INTEGER,
  history TEXT,               -- JSON: per iteration {iteration, cost, cached, config}
  measured INTEGER,           -- measurements taken by the finishing run (rest: from the DB)
  wall_s REAL, cpu_s REAL,    -- of the finishing run
  load1 REAL,                 -- 1-minute load average when it finished
  host_version TEXT,
  finished TEXT,              -- ISO 8601 UTC
  scene_parts TEXT            -- JSON: tt_scene_id_part of each part, to explain a changed id
)"""


def bit_reversed_order(n):
    """0..n-1 in an order whose every prefix is spread over the range (bit-reversal)."""
    bits = max(1, (n - 1).bit_length())
    keys = sorted(range(n), key=lambda i: int(format(i, "0%db" % bits)[::-1], 2))
    return keys


def camera_indices(n, samples=100):
    """n path samples spread evenly over 0..samples-1 (the host's --camera-index)."""
    if n >= samples:
        return list(range(samples))
    if n == 1:
        return [0]
    return [round(i * (samples - 1) / (n - 1)) for i in range(n)]


def settings_tag(a):
    tag = f"{a.iterations}it:{a.res}:{a.tune_spp}spp:{a.threads}t:{a.clock}:seed{a.seed}"
    return tag if a.tune_params == TUNE_PARAMS else tag + ":params=" + a.tune_params


def scene_file(a, name):
    """The scene file of `name`, generating the procedural scenes into --work once."""
    spec = SCENES[name]
    if isinstance(spec, str):
        path = spec if os.path.isabs(spec) else os.path.join(ROOT, spec)
        if not os.path.exists(path):
            sys.exit(f"baseline: {name}: {path} does not exist")
        return path
    kind, file = spec
    out = os.path.join(a.work, "scenes", kind)
    path = os.path.join(out, file)
    if not os.path.exists(path):
        tmp = out + ".tmp"
        shutil.rmtree(tmp, ignore_errors=True)
        print(f"baseline: generating the {kind} scene into {out}", flush=True)
        generate.main([kind, tmp])
        os.rename(tmp, out)
    return path


def all_jobs(a):
    cams = camera_indices(a.cameras)
    order = [cams[k] for k in bit_reversed_order(len(cams))]
    jobs = []
    for cam in order:
        for scene in a.scenes:
            for obj in a.objectives:
                jobs.append((scene, cam, obj))
    return jobs


def job_id(a, scene, cam, obj):
    return f"{scene}:{cam}:{obj}:{settings_tag(a)}"


def upgrade_jobs_table(con):
    """Adds the columns newer than a hybrid_jobs table (of an older baseline or dump)."""
    cols = {r[1] for r in con.execute("PRAGMA table_info(hybrid_jobs)")}
    if cols and "scene_parts" not in cols:
        con.execute("ALTER TABLE hybrid_jobs ADD COLUMN scene_parts TEXT")


def ensure_jobs_table(con):
    """Creates (or upgrades) hybrid_jobs once the file is a tunetrace tuning database (a
    schema version set by the host or tunetrace-mpi at the first job): the library refuses
    a version-0 file that already holds tables as another program's, so a new --db gets
    the tuning schema first and this table second. True when the table is there."""
    if not db.schema_version(con):
        return False
    con.execute(JOBS_SCHEMA)
    upgrade_jobs_table(con)
    con.commit()
    return True


def open_db(path):
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    con = sqlite3.connect(path, timeout=30)
    con.execute("PRAGMA journal_mode=WAL")
    ensure_jobs_table(con)
    return con


def done_jobs(con):
    if not ensure_jobs_table(con):
        return set()
    return {r[0] for r in con.execute("SELECT job FROM hybrid_jobs")}


def read_jobs(path):
    """Every row of hybrid_jobs in the baseline database at `path` as a dict (history and
    best_config parsed): what evaluate.py, epsilon.py and predict_cost.py read."""
    if not os.path.exists(path):
        sys.exit(f"baseline: {path}: no such baseline database")
    con = sqlite3.connect(f"file:{path}?mode=ro", uri=True, timeout=30)
    try:
        if not con.execute("SELECT count(*) FROM sqlite_master WHERE name = 'hybrid_jobs'").fetchone()[0]:
            sys.exit(f"baseline: {path}: no hybrid_jobs table (not a baseline of tools/hybrid/baseline.py)")
        cur = con.execute("SELECT * FROM hybrid_jobs")
        names = [d[0] for d in cur.description]
        out = [dict(zip(names, r)) for r in cur]
    finally:
        con.close()
    for r in out:
        r["history"] = json.loads(r["history"]) if r["history"] else []
        r["best_config"] = json.loads(r["best_config"]) if r["best_config"] else None
    return out


def dump_db(path, out):
    """--db as an xz-compressed SQL dump (sqlite3 iterdump), written atomically; the schema
    version (PRAGMA user_version, which iterdump leaves out) first, or the host would
    create the schema again in the restored file."""
    con = sqlite3.connect(path, timeout=30)
    with lzma.open(out + ".tmp", "wt", preset=9 | lzma.PRESET_EXTREME) as f:
        f.write("PRAGMA user_version=%d;\n" % db.schema_version(con))
        for line in con.iterdump():
            f.write(line + "\n")
    n = con.execute("SELECT count(*) FROM hybrid_jobs").fetchone()[0]
    con.close()
    os.replace(out + ".tmp", out)
    return n


def scene_ids(a, path):
    """(tt_scene_id, {part: id}) of a scene file as this checkout's host loads it (a 4x4 render
    with --stats), or (None, {}) when it does not load."""
    img = os.path.join(a.work, "restore_" + str(os.getpid()) + ".exr")
    r = host.run(a.host, ["--quiet", "--res", "4x4", "--spp", "1", "--threads", "1", "--out", img,
                          path], stats=True, log=subprocess.DEVNULL, check=False)
    if os.path.exists(img):
        os.remove(img)
    rec = r.stats or {}
    return rec.get("scene_id"), rec.get("scene_id_parts") or {}


def id_change(recorded, now):
    """Why a scene id changed, from the parts recorded with the rows and this checkout's."""
    if not recorded:
        return ("the dump does not record the parts of the id (geometry, materials, textures, "
                "lights), so which inputs changed is unknown")
    changed = [k for k in now if recorded.get(k) != now[k]]
    return "changed: " + (", ".join(changed) if changed else "none of the recorded parts")


def restore_db(a, dump):
    """A new --db from dump_db's file; hybrid_jobs.scene_file made this checkout's paths.
    Only the --scenes named are kept when --scenes is given. A scene whose id differs from
    the dump's is refused with what changed, or re-mapped with a warning (--remap-scenes)."""
    if os.path.exists(a.db):
        sys.exit(f"baseline: --restore: {a.db} exists (restore into a new file)")
    tmp = a.db + ".restore"
    for ext in ("", "-wal", "-shm"):
        if os.path.exists(tmp + ext):
            os.remove(tmp + ext)
    con = sqlite3.connect(tmp)
    with lzma.open(dump, "rt") as f:
        con.executescript(f.read())
    upgrade_jobs_table(con)
    if a.scenes_given:
        drop = [r[0] for r in con.execute("SELECT DISTINCT scene FROM hybrid_jobs")
                if r[0] not in a.scenes]
        for name in drop:
            db.drop_scenes(con, [r[0] for r in con.execute(
                "SELECT DISTINCT scene_id FROM hybrid_jobs WHERE scene = ?", (name,))])
            con.execute("DELETE FROM hybrid_jobs WHERE scene = ?", (name,))
    bad = []
    for name, sid, parts in con.execute("SELECT scene, scene_id, scene_parts FROM hybrid_jobs "
                                        "GROUP BY scene").fetchall():
        if name not in SCENES:
            bad.append(f"{name}: not a scene of this checkout (--scene {name}=FILE)")
            continue
        path = scene_file(a, name)
        got, got_parts = scene_ids(a, path)
        if got is None:
            bad.append(f"{name}: {path} does not load (run host on it for the message)")
            continue
        if got != sid:
            why = f"{name}: {path} has scene id {got}, the dump's rows {sid} ({id_change(json.loads(parts) if parts else None, got_parts)})"
            if not a.remap_scenes:
                bad.append(why)
                continue
            print(f"baseline: warning: --remap-scenes: {why}; its rows now count as measurements "
                  f"of the scene as this checkout has it", file=sys.stderr, flush=True)
            db.relabel_scene(con, sid, got)
        con.execute("UPDATE hybrid_jobs SET scene_file = ?, scene_id = ?, scene_parts = ? "
                    "WHERE scene = ?", (path, got, json.dumps(got_parts, sort_keys=True), name))
    con.commit()
    n = con.execute("SELECT count(*) FROM hybrid_jobs").fetchone()[0]
    m = db.count(con)
    con.close()
    if bad:
        os.remove(tmp)
        sys.exit("baseline: --restore: " + "; ".join(bad) +
                 ("" if a.remap_scenes else
                  ". If the scene changed on purpose, --remap-scenes keeps the rows under its new "
                  "id (with a warning): only do so when the change cannot alter build or render "
                  "cost"))
    os.replace(tmp, a.db)
    return n, m


def search_args(a):
    """The host arguments of a job besides its camera, objective and files."""
    return ["--plugin", a.tuner, "--tune", "accel_embree", "--tune-params", a.tune_params,
            "--iterations", str(a.iterations), "--tune-spp", str(a.tune_spp), "--spp", "1",
            "--res", a.res, "--threads", str(a.threads), "--clock", a.clock,
            "--seed", str(a.seed)]


def record_job(con, a, scene, path, cam, obj, st, wall, cpu, load1, version, finished):
    """The finished job's row of hybrid_jobs from the host's --stats JSON `st`."""
    t = st["tuning"]
    if not ensure_jobs_table(con):
        raise RuntimeError(f"baseline: {a.db} is not a tunetrace tuning database after the "
                           "job's host run (no schema version)")
    hist = [{"iteration": h["iteration"], "cost": h["cost"], "cached": h["cached"],
             "build_ms": h["build_ms"], "render_ms": h["render_ms"], "config": h["config"]}
            for h in t["history"]]
    con.execute("INSERT OR REPLACE INTO hybrid_jobs VALUES (?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,"
                "?,?,?,?,?,?)",
                (job_id(a, scene, cam, obj), scene, path, st.get("scene_id"), cam, obj,
                 a.iterations, a.tune_spp, a.res, a.threads, a.clock, a.seed, a.tuner,
                 a.tune_params, t["default_cost"], t["best_cost"],
                 json.dumps(t["best_config"], sort_keys=True), int(bool(t["converged"])),
                 json.dumps(hist), t["measured"], wall, cpu, load1, version, finished,
                 json.dumps(st.get("scene_id_parts"), sort_keys=True) if st.get("scene_id_parts") else None))


def mpi_job_list(a, jobs):
    """tunetrace-mpi's job list (mpi/README.md) for `jobs`: one item per job."""
    return {"jobs": [{"kind": "tune", "scene": scene_file(a, s), "camera": c, "objective": o,
                      "args": search_args(a)} for s, c, o in jobs]}


def import_mpi(a, con, version):
    """hybrid_jobs rows for the jobs tunetrace-mpi merged into --db with these settings."""
    names = {}
    for name in a.scenes:  # the paths scene_file gives, without generating anything
        spec = SCENES[name]
        path = (spec if os.path.isabs(spec) else os.path.join(ROOT, spec)) if isinstance(spec, str) \
            else os.path.join(a.work, "scenes", spec[0], spec[1])
        names[path] = name
    done = done_jobs(con)
    n = 0
    for m in db.merges(con):
        note, finished = m["note"], m["timestamp"]
        try:
            nt = json.loads(note)
            job = nt["job"]
        except (TypeError, ValueError, KeyError):
            continue
        scene = names.get(job.get("scene"))
        if job.get("kind") != "tune" or scene is None or job.get("args") != search_args(a) or \
                "stats" not in nt or job.get("objective") not in a.objectives:
            continue
        if job_id(a, scene, job["camera"], job["objective"]) in done:
            continue
        record_job(con, a, scene, job["scene"], job["camera"], job["objective"], nt["stats"],
                   nt.get("wall_s"), nt.get("cpu_s"), nt.get("load1"), version, finished)
        n += 1
    con.commit()
    return n


def run_mpi(a, jobs):
    """Runs `jobs` on a.mpi ranks: mpirun tunetrace-mpi over their job list."""
    path = os.path.join(a.work, "mpi_jobs.json")
    with open(path + ".tmp", "w") as f:
        json.dump(mpi_job_list(a, jobs), f, indent=1)
    os.replace(path + ".tmp", path)
    cmd = a.mpirun.split() + ["-np", str(a.mpi), "--bind-to", "core"]
    openmpi = os.path.basename(cmd[0]) in ("mpirun", "mpiexec", "orterun")
    if openmpi:  # a dead rank loses only its job (mpi/README.md "Faults")
        cmd += ["--enable-recovery"]
    if os.geteuid() == 0:  # containers: Open MPI refuses root unless told
        cmd += ["--allow-run-as-root"]
    if a.mpi > (os.cpu_count() or 1):
        cmd += ["--oversubscribe"]
    scratch = os.path.join(a.work, "scratch")
    os.makedirs(scratch, exist_ok=True)
    cmd += [a.mpi_driver, "--jobs", path, "--db", a.db, "--host", a.host, "--scratch", scratch]
    if a.max_jobs:
        cmd += ["--max-jobs", str(a.max_jobs)]
    print("baseline: " + " ".join(cmd), flush=True)
    rc = subprocess.run(cmd).returncode
    if rc == 0 and openmpi and not a.max_jobs:
        # mpirun --enable-recovery exits 0 whatever the ranks return: ask the database
        rc = subprocess.run([a.mpi_driver, "--jobs", path, "--db", a.db, "--host", a.host,
                             "--check"], stdout=subprocess.DEVNULL).returncode
    return rc


def run_job(a, con, scene, cam, obj, version):
    jid = job_id(a, scene, cam, obj)
    path = scene_file(a, scene)
    jdir = os.path.join(a.work, "jobs", scene)
    os.makedirs(jdir, exist_ok=True)
    stem = os.path.join(jdir, f"cam{cam:02d}_{obj.replace('+', '_')}")
    args = ["--quiet", "--camera-index", str(cam), "--objective", obj] + search_args(a) + \
        ["--db", a.db, "--out", stem + ".exr", path]
    try:
        r = host.run(a.host, args, stats=stem + ".json", log=stem + ".log")
    except host.HostError as e:
        print(f"baseline: job {jid} failed: {e}", file=sys.stderr, flush=True)
        return False
    finally:
        for ext in (".exr", ".png"):  # the image of 1-spp tuning passes is of no use here
            if os.path.exists(stem + ext):
                os.remove(stem + ext)
    record_job(con, a, scene, path, cam, obj, r.stats, r.wall_s, r.cpu_s, os.getloadavg()[0],
               version, time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()))
    con.commit()
    return True


def main(argv=None):
    ap = cli.parser(__doc__)
    ap.add_argument("--db", required=True, help="tuning database (created if missing)")
    ap.add_argument("--work", required=True, help="folder for job stats/logs and generated scenes")
    ap.add_argument("--scenes", default=",".join(DEFAULT_SCENES),
                    help="comma-separated names of " + ", ".join(SCENES))
    ap.add_argument("--scene", action="append", default=[], metavar="NAME=FILE",
                    help="another scene with a camera path (repeatable); --scenes then defaults "
                         "to these")
    ap.add_argument("--objectives", default=",".join(OBJECTIVES))
    ap.add_argument("--cameras", type=int, default=30, help="path samples per scene (thesis 100)")
    ap.add_argument("--iterations", type=int, default=40, help="Nelder-Mead iterations (thesis 80)")
    ap.add_argument("--res", default="128x128")
    ap.add_argument("--tune-spp", type=int, default=1)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--clock", default="cpu", choices=["cpu", "wall"])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--tuner", default="tuner_nm")
    ap.add_argument("--tune-params", default=TUNE_PARAMS, help="searched accel_embree parameters")
    ap.add_argument("--list", action="store_true", help="print the jobs (done/todo) and exit")
    ap.add_argument("--job", action="append", default=[],
                    help="run only this job SCENE:CAMERA:OBJECTIVE (repeatable)")
    ap.add_argument("--max-jobs", type=int, default=0, help="stop after this many new jobs")
    ap.add_argument("--shard", default="0/1", help="K/N: run only the jobs whose index in the "
                    "job order is K modulo N (N workers share one DB)")
    ap.add_argument("--mpi", type=int, default=0, metavar="N",
                    help="run the jobs on N MPI ranks (tunetrace-mpi, one merged --db)")
    ap.add_argument("--mpirun", default="mpirun", help="the MPI launcher command (--mpi)")
    ap.add_argument("--mpi-driver", help="tunetrace-mpi (default: the one of the host's build)")
    ap.add_argument("--emit-jobs", metavar="FILE",
                    help="write tunetrace-mpi's job list of the jobs to run and exit")
    ap.add_argument("--import-mpi", action="store_true",
                    help="record the jobs tunetrace-mpi merged into --db in hybrid_jobs, exit")
    ap.add_argument("--dump", metavar="FILE.sql.xz",
                    help="write --db as an xz-compressed SQL dump and exit")
    ap.add_argument("--restore", metavar="FILE.sql.xz",
                    help="create --db (a new file) from a --dump, scene files of this checkout, exit "
                         "(with --scenes: only those scenes' rows)")
    ap.add_argument("--remap-scenes", action="store_true",
                    help="with --restore: keep the rows of a scene whose id differs from the dump's "
                         "under this checkout's id (warns, naming what changed)")
    a = ap.parse_args(argv)
    for spec in a.scene:
        name, _, path = spec.partition("=")
        if not name or not path or not os.path.exists(path):
            ap.error(f"--scene {spec!r}: expected NAME=FILE of an existing scene")
        SCENES[name] = os.path.abspath(path)
    if a.scene and a.scenes == ",".join(DEFAULT_SCENES):
        a.scenes = ",".join(spec.partition("=")[0] for spec in a.scene)
    a.scenes_given = a.scenes != ",".join(DEFAULT_SCENES)
    a.scenes = [s for s in a.scenes.split(",") if s]
    a.objectives = [o for o in a.objectives.split(",") if o]
    for s in a.scenes:
        if s not in SCENES:
            ap.error(f"--scenes: unknown scene {s!r} (known: {', '.join(SCENES)})")
    for o in a.objectives:
        if o not in OBJECTIVES:
            ap.error(f"--objectives: unknown objective {o!r} (known: {', '.join(OBJECTIVES)})")
    if not 1 <= a.cameras <= 100:
        ap.error("--cameras: expected 1..100 (the host's path samples)")
    if a.iterations < 1:
        ap.error("--iterations: expected >= 1")
    jobs = all_jobs(a)
    if a.job:
        want = []
        for spec in a.job:
            parts = spec.split(":")
            if len(parts) != 3 or parts[0] not in SCENES or parts[2] not in a.objectives or \
                    not parts[1].isdigit() or not 0 <= int(parts[1]) < 100:
                ap.error(f"--job {spec!r}: expected SCENE:CAMERA:OBJECTIVE, CAMERA in 0..99, "
                         f"SCENE one of {', '.join(SCENES)}, OBJECTIVE one of {', '.join(OBJECTIVES)}")
            want.append((parts[0], int(parts[1]), parts[2]))
        jobs = want
    if a.mpi < 0:
        ap.error("--mpi: expected a number of ranks >= 1")
    os.makedirs(a.work, exist_ok=True)
    if a.dump:
        if not os.path.exists(a.db):
            sys.exit(f"baseline: --dump: {a.db} does not exist")
        print(f"baseline: {dump_db(a.db, a.dump)} jobs of {a.db} dumped to {a.dump}", flush=True)
        return 0
    a.host = host.find(a.host)
    if a.restore:
        n, m = restore_db(a, a.restore)
        print(f"baseline: {a.db} restored from {a.restore}: {n} jobs, {m} samples", flush=True)
        return 0
    con = open_db(a.db)
    version = host.version(a.host)
    imported = import_mpi(a, con, version)
    if imported:
        print(f"baseline: {imported} jobs merged by tunetrace-mpi recorded in hybrid_jobs", flush=True)
    if a.import_mpi:
        return 0
    done = done_jobs(con)
    if a.list:
        for s, c, o in jobs:
            print(("done " if job_id(a, s, c, o) in done else "todo ") + f"{s}:{c}:{o}")
        return 0
    try:
        k, nsh = (int(x) for x in a.shard.split("/"))
        assert nsh >= 1 and 0 <= k < nsh
    except (ValueError, AssertionError):
        ap.error(f"--shard {a.shard!r}: expected K/N with 0 <= K < N")
    per = len(a.objectives)  # both objectives of a (scene, camera) go to one worker
    jobs = [j for i, j in enumerate(jobs) if (i // per) % nsh == k]
    todo = [j for j in jobs if job_id(a, *j) not in done]
    print(f"baseline: {len(jobs)} jobs, {len(jobs) - len(todo)} already in {a.db}, {len(todo)} to run "
          f"({settings_tag(a)})", flush=True)
    for s in dict.fromkeys(s for s, _, _ in todo):
        scene_file(a, s)
    if a.emit_jobs:
        with open(a.emit_jobs + ".tmp", "w") as f:
            json.dump(mpi_job_list(a, todo), f, indent=1)
        os.replace(a.emit_jobs + ".tmp", a.emit_jobs)
        print(f"baseline: {len(todo)} jobs written to {a.emit_jobs}; then --import-mpi", flush=True)
        return 0
    if a.mpi:
        if not todo:
            return 0
        a.mpi_driver = a.mpi_driver or host.build_path(a.host, "mpi", "tunetrace-mpi")
        if not os.access(a.mpi_driver, os.X_OK):
            sys.exit(f"baseline: --mpi-driver {a.mpi_driver} is not an executable (tunetrace-mpi "
                     "is built when MPI is found: tools/bootstrap.sh installs Open MPI)")
        rc = run_mpi(a, todo)
        n = import_mpi(a, con, version)
        print(f"baseline: {n} jobs of this MPI run recorded in hybrid_jobs", flush=True)
        return rc
    t0 = time.time()
    failed = 0
    for k, (s, c, o) in enumerate(todo):
        if a.max_jobs and k >= a.max_jobs:
            break
        ok = run_job(a, con, s, c, o, version)
        failed += not ok
        el = time.time() - t0
        eta = el / (k + 1) * (len(todo) - k - 1)
        print(f"[{k + 1}/{len(todo)}] {s}:{c}:{o} {'ok' if ok else 'FAILED'}  elapsed {el / 60:.1f} min, "
              f"eta {eta / 60:.0f} min, load {os.getloadavg()[0]:.1f}", flush=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
