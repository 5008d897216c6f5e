"""A 20 kg foot (0.22 x 0.096 m sole of four 2 cm spheres) resting 2 s on a cohesive soil (c = 5 kPa, tan(phi) =
0.2, no bulldozing), then loaded at once from its weight W to 4 W (a downward push of 3 W): its contacts' friction
limit, sum of mu F_N over the sole contacts, against Mohr-Coulomb's c A + F_N tan(phi) for the same F_N, averaged
over windows after the step, with the traction mobilised (j set to 1 m). STEP=down: the reverse, 2 s under 4 W then released to W. CFG overrides ForcesConfig settings."""
import os
import sys
from pathlib import Path
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "soil_review_cpu"))
from common import (  # noqa: E402 - the outside review's foot world
    G, PARAM_NAMES, SOIL_PRESETS, foot_model, make, np, register_custom_soil, step,
)
M = 20.0; L, B = 0.22, 0.096; A = L * B
p = SOIL_PRESETS["mud"]
register_custom_soil("cohesive", **{q: getattr(p, q)[0] for q in PARAM_NAMES} | dict(c=5.0e3, mu=0.2, bulldoze_c=0.0,
                                                                                      bulldoze_g=0.0), model=p.model)
soil = "cohesive"
mjm = foot_model(M); W = sum(mjm.body_mass) * G
m, d, f = make(mjm, soil, **eval(os.environ.get("CFG", "{}")))
down = os.environ.get("STEP") == "down"  # the reverse: 2 s under 4 W, then released to W
for _ in range(400): step(m, d, f, [[0.0, -3.0 * W if down else 0.0]])
f.foot_slip.fill_(1.0)  # the traction mobilised (j >> K), so the contacts carry the whole limit
lim, mc = [], []
for k in range(100):
    step(m, d, f, [[0.0, 0.0 if down else -3.0 * W]])
    n = int(d.nacon.numpy()[0])
    mu = d.contact.friction.numpy()[:n, 0]
    fn = float(f.foot_fn.numpy()[0, 0])
    lim.append(float((mu * fn / max(n, 1)).sum())); mc.append(5.0e3 * A + 0.2 * fn)
lim, mc = np.array(lim), np.array(mc)
print(os.environ.get("CFG", "{}"), "4 W -> W" if down else "W -> 4 W", "limit / Mohr-Coulomb, substeps 1-4:", np.round(lim[:4] / mc[:4], 2),
      "; mean over 0-50 / 50-150 / 150-500 ms:",
      *(f"{lim[a:b].sum() / mc[a:b].sum():.2f}" for a, b in ((0, 10), (10, 30), (30, 100))))
