# %% [markdown]
# # Fig. 9 of Gharib & Ghani (2013) from Python
#
# The frame's displacement with and without the LSL damper (`scenes/lpc-lsl.toml`), from the
# `lpc_damper` package (`pip install ./python`), then the same damper as an ensemble under its
# gap tolerance: the question an engineer can act on is the distribution, not one trajectory.
#
# Run as a script (`python examples/fig9.py [OUT.png]`) or cell by cell in Jupyter or VS Code.

# %%
import sys
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import lpc_damper as lpc

root = Path(__file__).resolve().parents[1] if "__file__" in globals() else Path.cwd()
scene = lpc.load_scene(root / "scenes" / "lpc-lsl.toml")

# %% The damper, and the bare frame (the same file without its balls).
with_damper = lpc.run(scene)
bare = scene.to_dict()
bare["balls"]["arrangement"] = ""
bare.pop("tolerances", None)
without = lpc.run(lpc.Scene.from_dict(bare, name="no damper"))

# %% Fig. 9: xs(t), mm.
fig, (ax, hist) = plt.subplots(1, 2, figsize=(11, 4), gridspec_kw={"width_ratios": [2, 1]})
ax.plot(without.t, 1e3 * without.xs, color="0.6", lw=1, label="without damper")
ax.plot(with_damper.t, 1e3 * with_damper.xs, color="C0", lw=1, label="LSL damper")
ax.set(xlabel="t (s)", ylabel="xs (mm)", title="Fig. 9: frame displacement", xlim=(0, 5))
ax.legend()

# %% 2000 members under the scene's gap tolerance (each ball within +-0.02 Rr): when does the
# energy fall to 1 % of E0?
table = lpc.ensemble(scene, 2000)
t99 = table["dissipation_time_99"]
hist.hist(t99[np.isfinite(t99)], bins=40, color="C0")
q05, q50, q95 = np.nanquantile(t99, [0.05, 0.5, 0.95])
hist.axvline(with_damper.metrics["dissipation_time_99"], color="k", ls="--", label="nominal run")
hist.set(xlabel="energy at 1 % of E0 (s)", ylabel="members", title=f"median {q50:.2f} s, 5-95 % [{q05:.2f}, {q95:.2f}] s")
hist.legend()
fig.tight_layout()

out = Path(sys.argv[1]) if len(sys.argv) > 1 and not sys.argv[1].startswith("-") else Path("fig9.png")
fig.savefig(out, dpi=120)
print(f"wrote {out}; settling {with_damper.metrics['settling_time']:.3f} s with the damper")
