"""The host program, found by one rule and run one way by every tool.

Which host: the tool's `--host PATH` (cli.HOST), else $TT_HOST, else build/host/host of the
checkout these tools belong to. find() says which rule gave a path that is not an
executable, and how to build one. A tool that needs more of a build than the host (the MPI
driver, a test binary, the built plugins) takes it from the host's build tree (build_path),
so one option names the build a tool measures.

run() runs it: the arguments as given, optionally under `nice`, its output shown, captured or
sent to a log file, `--stats` written to a file that is read back (and removed unless the
caller named it), the wall and CPU seconds of the process. A failure raises HostError, a
SystemExit whose message names the command, the exit status and the end of its output, so a
tool that does not catch it exits with that message and no traceback. render() is run() for
one measured render (--res, --no-db, --out, --stats kept): (stats, CPU seconds).
"""
import json
import os
import resource
import shutil
import subprocess
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DEFAULT = os.path.join(ROOT, "build", "host", "host")


class HostError(SystemExit):
    """The host could not be found or failed; str() is the whole message."""

    def __init__(self, message):
        super().__init__(message)
        self.message = message

    def __str__(self):
        return self.message


def find(path=None):
    """The host program as an absolute path: `path` (a tool's --host), else $TT_HOST, else
    build/host/host of this checkout. HostError if it is not an executable file."""
    if path:
        where = "--host"
    elif os.environ.get("TT_HOST"):
        path, where = os.environ["TT_HOST"], "$TT_HOST"
    else:
        path, where = DEFAULT, "the checkout's build"
    path = os.path.abspath(os.path.expanduser(path))
    if not (os.path.isfile(path) and os.access(path, os.X_OK)):
        raise HostError(f"host: {path} ({where}) is not an executable: build it (meson setup "
                        f"build && ninja -C build), or name one with --host PATH or $TT_HOST")
    return path


def build_dir(host):
    """The build tree the host program was built in (BUILD for BUILD/host/host), or None for
    an installed host."""
    d = os.path.dirname(os.path.dirname(os.path.abspath(host)))
    return d if os.path.exists(os.path.join(d, "meson-info")) else None


def build_path(host, *parts):
    """A file of the host's build tree (build_path(h, "mpi", "tunetrace-mpi")); HostError
    naming what is missing when the host is not in a build tree or the file is not built."""
    d = build_dir(host)
    if d is None:
        raise HostError(f"host: {host} is not in a build tree, so {os.path.join(*parts)} "
                        "cannot be found beside it: give --host BUILD/host/host")
    path = os.path.join(d, *parts)
    if not os.path.exists(path):
        raise HostError(f"host: {path} is not built (ninja -C {d})")
    return path


def read_stats(path):
    """A host --stats file as a dict; HostError naming the file if it is missing or cut."""
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError) as e:
        raise HostError(f"host: --stats {path}: {e}") from None


class Result:
    """What run() returns: command, returncode, stdout/stderr (captured text, else None),
    stats (the --stats JSON, else None), wall_s, cpu_s (user + system of the process)."""

    def __init__(self, command, returncode, stdout, stderr, stats, wall_s, cpu_s):
        self.command, self.returncode = command, returncode
        self.stdout, self.stderr, self.stats = stdout, stderr, stats
        self.wall_s, self.cpu_s = wall_s, cpu_s

    def json(self):
        """The JSON object the host printed on stdout (--predict, --measure, --describe)."""
        text = self.stdout or ""
        start = text.find("{")
        try:
            return json.loads(text[start:]) if start >= 0 else json.loads(text)
        except ValueError as e:
            raise HostError(f"host: {' '.join(self.command)}: expected JSON on stdout ({e}):\n"
                            f"{text[-1500:]}") from None


def _tail(text, n=3000):
    return text[-n:] if text else ""


def run(host, args, *, stats=None, nice=None, capture=False, log=None, check=True, env=None,
        cwd=None, timeout=None):
    """Runs `host` with `args` (a list; paths may be path-like) and returns a Result.

    stats    True: a temporary --stats file, read into Result.stats and removed; a path:
             --stats PATH, read back and kept (a tool's cache)
    nice     run under `nice -n NICE`
    capture  stdout and stderr as text in the Result (else they go to this process')
    log      a file path: stdout and stderr into it (replaced); subprocess.DEVNULL: dropped
    check    a non-zero exit raises HostError with the command and the end of the output
    env, cwd, timeout as for subprocess.run (a timeout raises HostError)."""
    cmd = ([] if nice is None else ["nice", "-n", str(nice)]) + [host]
    cmd += [os.fspath(x) for x in args]
    tmpdir = None
    if stats is True:
        tmpdir = tempfile.mkdtemp(prefix="tt_host_stats.")
        stats_path = os.path.join(tmpdir, "stats.json")
    else:
        stats_path = os.fspath(stats) if stats else None
    if stats_path:
        cmd += ["--stats", stats_path]
    kw = {"env": env, "cwd": cwd, "timeout": timeout, "text": True}
    log_file = None
    if capture:
        kw.update(stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    elif log is subprocess.DEVNULL:
        kw.update(stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    elif log:
        log_file = open(log, "w")
        kw.update(stdout=log_file, stderr=subprocess.STDOUT)
    ru0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.time()
    try:
        p = subprocess.run(cmd, **kw)
    except subprocess.TimeoutExpired:
        raise HostError(f"host: {' '.join(cmd)}: no exit after {timeout} s") from None
    except OSError as e:
        raise HostError(f"host: {' '.join(cmd)}: {e}") from None
    finally:
        if log_file:
            log_file.close()
    wall = time.time() - t0
    ru1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (ru1.ru_utime - ru0.ru_utime) + (ru1.ru_stime - ru0.ru_stime)
    try:
        if p.returncode != 0:
            if check:
                out = (p.stderr or "") + (p.stdout or "") if capture else ""
                if log and log is not subprocess.DEVNULL:
                    with open(log, errors="replace") as f:
                        out = f.read()
                raise HostError(f"host: {' '.join(cmd)}\nexit {p.returncode}\n{_tail(out)}"
                                .rstrip())
            st = None
        else:
            st = read_stats(stats_path) if stats_path else None
    finally:
        if tmpdir:
            shutil.rmtree(tmpdir, ignore_errors=True)
    return Result(cmd, p.returncode, p.stdout, p.stderr, st, wall, cpu)


def render(host, scene, extra, *, out, stats, res, threads=None, nice=None, log=None):
    """One measured render, as the chapter-4 tools take them: `host SCENE --res RES
    [--threads N] --no-db --quiet --out OUT` + extra, its --stats written to `stats` (kept)
    and read back. Returns (the --stats dict, CPU seconds of the host process)."""
    args = [scene, "--res", res] + (["--threads", str(threads)] if threads else [])
    r = run(host, args + ["--no-db", "--quiet", "--out", out] + list(extra), stats=stats,
            nice=nice, log=log)
    return r.stats, r.cpu_s


def describe(host, plugin):
    """host --describe PLUGIN: the plugin's parameter space as a dict."""
    return run(host, ["--describe", plugin], capture=True).json()


def default_config(host, plugin):
    """The plugin's default configuration {name: value} (host --describe)."""
    return {p["name"]: p["value"] for p in describe(host, plugin)["parameters"]}


def version(host):
    """The first line of host --version ("unknown" if it prints nothing)."""
    r = run(host, ["--version"], capture=True, check=False)
    text = ((r.stdout or "") + (r.stderr or "")).strip()
    return text.splitlines()[0] if text else "unknown"
