"""Points a sequence's manifest at reference frames rendered in another folder (one
reference shared by inputs at several sample rates: render_noisy.sh).

  /usr/bin/python3 -m tools.taa.link_reference SEQ_DIR REF_DIR

REF_DIR is a `host --frames A:B --out REF_DIR/frame_%04d.exr --supersample K` folder (or a
--sequence folder with references); frame i of SEQ_DIR gets "reference": the relative path
of REF_DIR's frame with the same index. The manifest is rewritten atomically."""
import json
import os
import sys

from tools.tttools import cli


def main():
    ap = cli.parser(__doc__, host=False)
    ap.add_argument("seq", metavar="SEQ_DIR")
    ap.add_argument("ref", metavar="REF_DIR")
    a = ap.parse_args()
    seq, ref = a.seq, a.ref
    mpath = os.path.join(seq, "manifest.json")
    man = json.load(open(mpath))
    rman = json.load(open(os.path.join(ref, "manifest.json")))
    refs = {f["index"]: f["reference"] for f in rman["frames"] if "reference" in f}
    for f in man["frames"]:
        if f["index"] not in refs:
            sys.exit(f"link_reference.py: {ref}/manifest.json: no reference for frame {f['index']} "
                     f"of {mpath}")
        f["reference"] = os.path.relpath(os.path.join(ref, refs[f["index"]]), seq)
    man["reference_scale"] = rman.get("reference_scale")
    man["reference_spp"] = rman.get("spp")
    tmp = mpath + ".tmp"
    with open(tmp, "w") as fh:
        json.dump(man, fh, indent=1)
    os.replace(tmp, mpath)


if __name__ == "__main__":
    main()
