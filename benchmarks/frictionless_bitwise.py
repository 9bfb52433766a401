"""The frictionless demos bit for bit across versions: dump their arrays, compare two dumps.

Runs the Taylor bar (mono, arlequin, graded; 4 cells, 10 µs), the two bars (both methods, and
the level-set model with central differences) and the 2D/3D block impacts (θ-scheme and
explicit), and pickles their computed arrays. Run it with the old version first:

    git worktree add /tmp/old <commit>
    PYTHONPATH=/tmp/old python benchmarks/frictionless_bitwise.py old.pkl
    python benchmarks/frictionless_bitwise.py new.pkl
    python benchmarks/frictionless_bitwise.py --compare old.pkl new.pkl
"""

import pickle
import sys
import warnings

import numpy as np


def _equal(x, y) -> bool:
    if isinstance(x, dict):
        return set(x) == set(y) and all(_equal(x[k], y[k]) for k in x)
    if isinstance(x, tuple):
        return len(x) == len(y) and all(_equal(p, q) for p, q in zip(x, y))
    return np.array_equal(np.asarray(x), np.asarray(y))


if sys.argv[1] == "--compare":
    a, b = (pickle.load(open(p, "rb")) for p in sys.argv[2:4])
    for k in a:
        print(k, "bitwise equal" if _equal(a[k], b.get(k)) else "DIFFERENT")
    raise SystemExit(0)

warnings.simplefilter("ignore")
from arlequin.demos.block_impact import run_block_impact  # noqa: E402
from arlequin.demos.taylor_bar import run_taylor_bar  # noqa: E402
from arlequin.demos.two_bars import run_two_bars  # noqa: E402

out = {}
for model in ("mono", "arlequin", "graded"):
    r = run_taylor_bar(model=model, elements_radial=4, t_end=10e-6)
    out["taylor_" + model] = (np.asarray(r.u), {k: np.asarray(v) for k, v in r.history.items()})
r = run_two_bars(method="both")
re_ = run_two_bars(method="levelset", integrator="explicit")
out["two_bars_explicit"] = np.asarray(re_.interface_velocity)
out["two_bars"] = (np.asarray(r.interface_velocity), np.asarray(r.newmark.interface_velocity))
CASES = (("plane", "theta"), ("block", "theta"), ("plane", "explicit"), ("block", "explicit"))
for dim in (2, 3):
    for target, integ in CASES:
        cfl = {"cfl": 0.9} if integ == "explicit" else {}
        b = run_block_impact(dim=dim, target=target, integrator=integ, **cfl)
        out[f"block_{dim}_{target}_{integ}"] = {
            k: np.asarray(v)
            for k, v in vars(b).items()
            if isinstance(v, (np.ndarray, list)) and np.asarray(v).dtype.kind == "f"
        }
with open(sys.argv[1], "wb") as f:
    pickle.dump(out, f)
print("ok", list(out))
