"""Bad plugins, measured (#13): hands `host` broken plugin files and counts how each is
handled. Every kind must be rejected with exit 3 and a message naming the file as `--plugin FILE` (a
4x4 render of the Cornell box); inside a `--plugin-path DIR --list-plugins` listing every
broken file must be rejected the same way, while a well-formed file whose interface tables or
init are broken may be listed (a listing reads entry tables only); the built plugins must
still be listed. A crash, a hang (60 s) or another exit code is a failure.

  /usr/bin/python3 -m tools.probe_plugins [--host BUILD/host/host]

Kinds: the loader fixtures broken in one way each (tests/fixtures: wrong ABI major, no entry
symbol, wrong kind, no interface, init fails, short tables, NULL required functions), and
files made from a real plugin (tuner_nm.so): cut short at 13 sizes from 0 bytes to one byte
short, not ELF (text, random bytes), ELF header fields broken (32-bit class, big-endian,
another machine, not a shared object, program headers past the end, a segment's file size
past the end), and what is not a regular file (a folder, a FIFO, a link to /dev/zero, a
dangling link). Prints one line per kind and a summary; exits 1 on any failure."""
import os
import random
import struct
import subprocess
import sys
import tempfile

from tools.tttools import cli, host

ROOT = host.ROOT
FIXTURES = ["wrong_major", "no_entry", "wrong_kind", "no_iface", "init_fails", "short_table",
            "short_iface", "null_tuner", "null_post", "null_sampler"]


def patched(data, offset, fmt, value):
    b = bytearray(data)
    struct.pack_into(fmt, b, offset, value)
    return bytes(b)


def made_files(real):
    """(kind, bytes) pairs made from the bytes of a real plugin."""
    n = len(real)
    out = []
    for cut in [0, 1, 4, 16, 52, 63, 64, 200, 1024, 4096, 16384, n // 2, n - 1]:
        out.append(("cut at %d of %d bytes" % (cut, n), real[:cut]))
    out.append(("a text file", b"this is not a plugin\n" * 20))
    out.append(("random bytes", random.Random(1).randbytes(65536)))
    out.append(("random bytes behind an ELF magic", b"\x7fELF" + random.Random(2).randbytes(65536)))
    out.append(("ELF class 32-bit", patched(real, 4, "B", 1)))
    out.append(("ELF big-endian", patched(real, 5, "B", 2)))
    out.append(("ELF for another machine (AArch64)", patched(real, 18, "<H", 183)))
    out.append(("ELF not a shared object (ET_REL)", patched(real, 16, "<H", 1)))
    out.append(("program headers past the end", patched(real, 32, "<Q", n + 4096)))
    out.append(("program header count huge", patched(real, 56, "<H", 0xFFFF)))
    # the first PT_LOAD segment's file size past the end of the file
    phoff, = struct.unpack_from("<Q", real, 32)
    phentsize, phnum = struct.unpack_from("<HH", real, 54)
    for i in range(phnum):
        off = phoff + i * phentsize
        if struct.unpack_from("<I", real, off)[0] == 1:  # PT_LOAD
            out.append(("a PT_LOAD segment past the end", patched(real, off + 32, "<Q", 4 * n)))
            break
    return out


def run(cmd, timeout=60):
    try:
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=timeout)
        return p.returncode, p.stdout.decode("utf-8", "replace")
    except subprocess.TimeoutExpired:
        return "hang", ""


def main():
    ap = cli.parser(__doc__)
    a = ap.parse_args()
    exe = host.find(a.host)
    scene = os.path.join(ROOT, "scenes", "cornell-box", "scene.json")
    with open(host.build_path(exe, "plugins", "tuner_nm", "tuner_nm.so"), "rb") as f:
        real = f.read()
    ok = bad = list_rejected = 0
    with tempfile.TemporaryDirectory(prefix="tt_probe_plugins_") as tmp:
        cases = []  # (kind, path)
        for name in FIXTURES:
            cases.append(("fixture " + name, host.build_path(exe, "tests", "fixtures",
                                                            "fixture_%s.so" % name)))
        for i, (kind, data) in enumerate(made_files(real)):
            d = os.path.join(tmp, "case%02d" % i)
            os.mkdir(d)
            p = os.path.join(d, "bad_plugin.so")
            with open(p, "wb") as f:
                f.write(data)
            cases.append((kind, p))
        specials = [("a folder named .so", lambda p: os.mkdir(p)),
                    ("a FIFO named .so", lambda p: os.mkfifo(p)),
                    ("a link to /dev/zero", lambda p: os.symlink("/dev/zero", p)),
                    ("a dangling link", lambda p: os.symlink(os.path.join(tmp, "nowhere.so"), p))]
        for i, (kind, make) in enumerate(specials):
            d = os.path.join(tmp, "special%d" % i)
            os.mkdir(d)
            p = os.path.join(d, "bad_plugin.so")
            make(p)
            cases.append((kind, p))
        for kind, path in cases:
            out = os.path.join(tmp, "out.exr")
            rc1, log1 = run([exe, "--plugin", path, "--spp", "1", "--res", "4x4", "--out", out,
                             scene])
            # a listing of a folder holding it (fixtures: a folder with a link to it)
            d, listed = os.path.dirname(path), path
            fixture = kind.startswith("fixture")
            if fixture:
                d = os.path.join(tmp, "list_" + os.path.basename(path))
                os.mkdir(d)
                listed = os.path.join(d, os.path.basename(path))
                os.symlink(path, listed)
            rc2, log2 = run([exe, "--plugin-path", d, "--list-plugins"])
            loaded_ok = rc1 == 3 and path in log1
            # the listing reads entry tables only (no init, no interface tables): a fixture
            # broken past its entry table is listed, not rejected; it must not crash, hang or
            # hide the good plugins
            list_rejects = rc2 == 3 and listed in log2 and "rejected" in log2
            list_ok = "integrator_pt" in log2 and (list_rejects or (fixture and rc2 == 0))
            good = loaded_ok and list_ok
            ok += good
            bad += not good
            list_rejected += list_rejects
            print("%-4s %-40s --plugin: exit %-4s --list-plugins: exit %s%s" %
                  ("ok" if good else "FAIL", kind, rc1, rc2,
                   "" if list_rejects else " (listed: broken past the entry table)"))
            if not good:
                print("     " + (log1.strip().splitlines() or ["(no output)"])[-1])
                print("     " + (log2.strip().splitlines() or ["(no output)"])[-1])
    print("probe_plugins: %d kinds of bad plugin: %d handled (--plugin: exit 3 naming the "
          "file), %d failed; --list-plugins rejected %d of them (the others are broken past "
          "the entry table, which a listing does not go)" % (ok + bad, ok, bad, list_rejected))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
