"""Linear interpolation of two weights files of the same shape (numpy only):
OUT = (1 - A) * FROM + A * TO, layer by layer (weights and biases). With TO fine-tuned from
FROM (train.py --init FROM), A between 0 and 1 walks the straight line from the original to
the fine-tuned network, trading what the fine-tuning gained against what it lost
(issue #19, session 6).

  /usr/bin/python3 -m tools.taa.blend_weights FROM.ttw TO.ttw A OUT.ttw"""

import numpy as np

from tools.taa import ttw
from tools.tttools import cli


def blend(a_model, b_model, alpha):
    if (a_model.width, a_model.hidden, a_model.flags, len(a_model.layers)) != \
            (b_model.width, b_model.hidden, b_model.flags, len(b_model.layers)):
        raise SystemExit("blend_weights.py: the two files have different shapes")
    out = []
    for la, lb in zip(a_model.layers, b_model.layers):
        if la.weight.shape != lb.weight.shape or (la.role, la.act) != (lb.role, lb.act):
            raise SystemExit("blend_weights.py: layers differ in shape")
        w = ((1.0 - alpha) * la.weight.astype(np.float64) + alpha * lb.weight).astype(np.float32)
        b = ((1.0 - alpha) * la.bias.astype(np.float64) + alpha * lb.bias).astype(np.float32)
        out.append(ttw.Layer(la.role, la.cin, la.cout, la.k, la.sets, la.act, w, b))
    return ttw.Model(a_model.width, a_model.hidden, out, a_model.motion_scale, a_model.flags)


def main():
    ap = cli.parser(__doc__, host=False)
    ap.add_argument("src", metavar="FROM.ttw")
    ap.add_argument("dst", metavar="TO.ttw")
    ap.add_argument("alpha", metavar="A", type=float, help="0: FROM, 1: TO")
    ap.add_argument("out", metavar="OUT.ttw")
    a = ap.parse_args()
    ttw.write(blend(ttw.read(a.src), ttw.read(a.dst), a.alpha), a.out)


if __name__ == "__main__":
    main()
