"""Crash safety, measured (#13): kills `host` with SIGKILL at random moments of a render and
of a tuning run, and checks what a kill may leave behind.

  /usr/bin/python3 -m tools.crash_safety [--host PATH] [--kills 100] \
      [--part render|tune|signal|both|all] [--seed 1]

Render: the host renders the Cornell box over the EXR, PNG and --stats record of the
previous trial, and is killed at a random moment (half of the kills uniform over a whole
run, half in its last fifth, where the outputs are written). Afterwards every output must be
byte for byte the previous one or a complete new one (the image reads back whole at the
right size with its metadata; the JSON parses with its fields); missing or truncated is a
failure. Temporaries (.NAME.tmp-XXXXXX) a kill leaves are counted, not failures.

Tuning: the host tunes accel_embree with tuner_nm into one database, killed at a random
moment; just before the kill the script reads the ids of the rows committed so far (another
connection, WAL). Afterwards PRAGMA integrity_check must say ok and every id read before
the kill must still be there. At the end one more tuning run into the same file must
succeed.

Signal (--part signal or all): SIGINT or SIGTERM at a random moment of a render, in a third
of the trials a second one 0-50 ms later. The host must exit 130 (0 if it finished first;
128 + the signal when a second one made it exit at once;
killed by the signal only before its handlers exist, while it loads the plugins and the scene), and every
output must be the previous one or a complete new one; after one signal and exit 130 the
image and record rendered so far must have been written.

Prints one summary line per part and exits 1 on any failure. meson runs a
short version (3 kills per part) in the render suite (test crash_safety)."""
import hashlib
import json
import os
import random
import signal
import statistics
import subprocess
import sys
import tempfile
import time

from tools.tttools import cli, host
from tools.tttools import db as tunedb


def digest(path):
    try:
        with open(path, "rb") as f:
            return hashlib.sha256(f.read()).hexdigest()
    except FileNotFoundError:
        return None


def image_complete(path, width, height):
    """True if the whole image reads back at width x height with its spp metadata."""
    try:
        import OpenImageIO as oiio
    except ImportError:
        return None
    inp = oiio.ImageInput.open(path)
    if not inp:
        return False
    try:
        spec = inp.spec()
        if spec.width != width or spec.height != height:
            return False
        pixels = inp.read_image()
        if pixels is None:
            return False
        return spec.getattribute("tunetrace:spp") is not None or spec.getattribute("spp") is not None
    finally:
        inp.close()


def stats_complete(path):
    try:
        with open(path) as f:
            rec = json.load(f)
        return all(k in rec for k in ("spp", "render_ms", "output"))
    except (OSError, ValueError):
        return False


def timed_run(args):
    t0 = time.monotonic()
    subprocess.run(args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
    return time.monotonic() - t0


def kill_at(args, delay, before_kill=None):
    """Starts args, sleeps `delay` s, calls before_kill(), SIGKILLs; returns (killed, result)."""
    p = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(delay)
    seen = before_kill() if before_kill else None
    killed = p.poll() is None
    if killed:
        p.send_signal(signal.SIGKILL)
    p.wait()
    return killed, seen


def temporaries(folder):
    return [n for n in os.listdir(folder) if ".tmp-" in n]


def render_part(host, scene, work, kills, rng):
    size = 96
    outs = {"exr": os.path.join(work, "box.exr"), "png": os.path.join(work, "box.png"),
            "stats": os.path.join(work, "box.json")}

    def args(seed):
        return [host, "--quiet", "--spp", "8", "--res", "%dx%d" % (size, size), "--seed",
                str(seed), "--out", outs["exr"], "--stats", outs["stats"], scene]

    first = subprocess.run(args(1), capture_output=True, text=True)
    if first.returncode != 0:
        print("render: the first run failed: " + first.stdout + first.stderr)
        return 1
    duration = statistics.median(timed_run(args(2)) for _ in range(3))
    counts = {k: {"old": 0, "new": 0, "lost": 0, "corrupt": 0} for k in outs}
    finished = 0
    failures = []
    for trial in range(kills):
        before = {k: digest(p) for k, p in outs.items()}
        if trial % 2:
            delay = duration * rng.uniform(0.8, 1.05)
        else:
            delay = duration * rng.uniform(0.0, 1.05)
        killed, _ = kill_at(args(100 + trial), delay)
        finished += not killed
        for k, p in outs.items():
            now = digest(p)
            if now is None:
                state = "lost"
            elif now == before[k]:
                state = "old"
            elif k == "stats":
                state = "new" if stats_complete(p) else "corrupt"
            else:
                ok = image_complete(p, size, size)
                state = "new" if ok or ok is None else "corrupt"
            counts[k][state] += 1
            if state in ("lost", "corrupt"):
                failures.append("trial %d (kill at %.3f s): %s is %s" % (trial, delay, p, state))
    left = temporaries(work)
    for f in failures:
        print("FAIL render: " + f)
    print("render: %d kills (%d runs finished first; a run takes %.2f s): %s; %d temporaries "
          "left behind" % (kills, finished, duration, "; ".join(
              "%s old %d, new %d, lost %d, corrupt %d" % (k, c["old"], c["new"], c["lost"],
                                                          c["corrupt"])
              for k, c in counts.items()), len(left)))
    return 1 if failures else 0


def tune_part(host, scene, work, kills, rng):
    db = os.path.join(work, "tuning.db")

    def args(seed):
        return [host, "--quiet", "--plugin", "tuner_nm", "--iterations", "40", "--spp", "1",
                "--res", "16x16", "--seed", str(seed), "--db", db,
                "--out", os.path.join(work, "tuned.exr"), scene]

    duration = statistics.median(timed_run(args(s)) for s in (1, 2))

    def committed():
        try:
            return tunedb.row_ids(db)
        except tunedb.SQLiteError as e:
            return e

    failures = []
    seen_total = lost_total = 0
    integrity_ok = 0
    finished = 0
    for trial in range(kills):
        delay = duration * rng.uniform(0.05, 1.0)
        killed, seen = kill_at(args(1000 + trial), delay, committed)
        finished += not killed
        if isinstance(seen, Exception):
            failures.append("trial %d: reading before the kill: %s" % (trial, seen))
            continue
        check = tunedb.integrity(db)
        after = tunedb.row_ids(db)
        integrity_ok += check == "ok"
        if check != "ok":
            failures.append("trial %d: integrity_check: %s" % (trial, check))
        lost = seen - after
        seen_total += len(seen)
        lost_total += len(lost)
        if lost:
            failures.append("trial %d (kill at %.3f s): %d committed rows lost: %s"
                            % (trial, delay, len(lost), sorted(lost)[:10]))
    final = subprocess.run(args(99999), capture_output=True, text=True)
    if final.returncode != 0:
        failures.append("a tuning run after the kills failed (exit %d): %s"
                        % (final.returncode, final.stderr[-1000:]))
    rows = tunedb.count(db)
    for f in failures:
        print("FAIL tune: " + f)
    print("tune: %d kills (%d runs finished first; a run takes %.2f s): integrity_check ok "
          "%d/%d; %d committed rows read just before the kills (summed), %d lost; %d rows in "
          "the database; the run after the kills %s"
          % (kills, finished, duration, integrity_ok, kills, seen_total,
             lost_total, rows,
             "succeeded" if final.returncode == 0 else "failed"))
    return 1 if failures else 0


def signal_part(host, scene, work, kills, rng):
    """SIGINT/SIGTERM at random moments of a render, a second one soon after in a third of
    the trials: the host must exit 130 having written what it rendered (or 0 if it finished
    first); every output is the previous one or a complete new one."""
    size = 96
    outs = {"exr": os.path.join(work, "sig.exr"), "stats": os.path.join(work, "sig.json")}

    def args(seed):
        return [host, "--quiet", "--spp", "64", "--res", "%dx%d" % (size, size), "--seed",
                str(seed), "--out", outs["exr"], "--stats", outs["stats"], scene]

    first = subprocess.run(args(1), capture_output=True, text=True)
    if first.returncode != 0:
        print("signal: the first run failed: " + first.stdout + first.stderr)
        return 1
    duration = statistics.median(timed_run(args(2)) for _ in range(3))
    codes = {}
    states = {k: {"old": 0, "new": 0, "lost": 0, "corrupt": 0} for k in outs}
    doubles = 0
    failures = []
    for trial in range(kills):
        before = {k: digest(p) for k, p in outs.items()}
        sig = signal.SIGINT if trial % 2 == 0 else signal.SIGTERM
        double = trial % 3 == 2
        doubles += double
        delay = duration * rng.uniform(0.0, 1.05)
        p = subprocess.Popen(args(200 + trial), stdout=subprocess.DEVNULL,
                             stderr=subprocess.DEVNULL)
        time.sleep(delay)
        if p.poll() is None:
            p.send_signal(sig)
            if double:
                time.sleep(rng.uniform(0.0, 0.05))
                if p.poll() is None:
                    p.send_signal(sig)
        try:
            rc = p.wait(timeout=120)
        except subprocess.TimeoutExpired:
            p.kill()
            rc = "hang"
            failures.append("trial %d: no exit 120 s after the signal" % trial)
        codes[rc] = codes.get(rc, 0) + 1
        # exit 130 or 0; a signal before the handlers are installed (plugin and scene loading)
        # ends the process by the default action, which writes nothing (-SIGNAL)
        # a second signal exits at once: 128 + the signal (130 for SIGINT, 143 for SIGTERM)
        allowed = (0, 130, -int(sig)) + ((128 + int(sig),) if double else ())
        if rc not in allowed:
            failures.append("trial %d (signal at %.3f s): exit %s" % (trial, delay, rc))
        for k, path in outs.items():
            now = digest(path)
            if now is None:
                state = "lost"
            elif now == before[k]:
                state = "old"
            elif k == "stats":
                state = "new" if stats_complete(path) else "corrupt"
            else:
                ok = image_complete(path, size, size)
                state = "new" if ok or ok is None else "corrupt"
            states[k][state] += 1
            if state in ("lost", "corrupt"):
                failures.append("trial %d (signal at %.3f s): %s is %s" % (trial, delay, path, state))
            # one signal and exit 130: what was rendered so far must have been written
            if rc == 130 and not double and state == "old":
                failures.append("trial %d: exit 130 after one signal but %s was not written"
                                % (trial, path))
    for f in failures:
        print("FAIL signal: " + f)
    print("signal: %d runs signalled (SIGINT/SIGTERM alternately, %d with a second signal; a run "
          "takes %.2f s): exit codes %s; %s; %d temporaries left behind" % (
              kills, doubles, duration,
              ", ".join("%s: %d" % (k, v) for k, v in sorted(codes.items(), key=str)),
              "; ".join("%s old %d, new %d, lost %d, corrupt %d" % (
                  k, c["old"], c["new"], c["lost"], c["corrupt"]) for k, c in states.items()),
              len(temporaries(work))))
    return 1 if failures else 0


def main():
    ap = cli.parser(__doc__)
    ap.add_argument("--kills", type=int, default=100, help="kills per part")
    ap.add_argument("--part", choices=("render", "tune", "signal", "both", "all"), default="both",
                    help="both: render and tune; all: also signal")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--keep", help="work folder to keep (default: a temporary one)")
    a = ap.parse_args()
    exe = host.find(a.host)
    scene = os.path.join(host.ROOT, "scenes", "cornell-box", "scene.json")
    rng = random.Random(a.seed)
    with tempfile.TemporaryDirectory(prefix="tt_crash_safety_") as tmp:
        work = a.keep or tmp
        os.makedirs(work, exist_ok=True)
        rc = 0
        if a.part in ("render", "both", "all"):
            rc |= render_part(exe, scene, work, a.kills, rng)
        if a.part in ("tune", "both", "all"):
            rc |= tune_part(exe, scene, work, a.kills, rng)
        if a.part in ("signal", "all"):
            rc |= signal_part(exe, scene, work, a.kills, rng)
    return rc


if __name__ == "__main__":
    sys.exit(main())
