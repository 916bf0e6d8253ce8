"""cui2025's fuzzy rollout evaluation (IDWA, §3.2): memberships, a rule base, weighted-average defuzzification.

cui2025 fixes the structure — three inputs (heading deviation, normalised speed,
minimum obstacle distance), three triangular terms each, a rule base that "prioritises
low deviation, high velocity and safe clearance", with the typical rules "if heading is
small and velocity is fast and obstacle is far then the evaluation is high" and "if
heading is large or obstacle is close then the evaluation is low", defuzzified by the
weighted average — and the weights 0.4 / 0.3 / 0.3 for heading, velocity and safety.
It gives no breakpoints and no full table; these are ours.

**Inputs and memberships.** Each input has a left shoulder, a triangle and a right
shoulder meeting at three breakpoints, so the three degrees of every input sum to 1
(a Ruspini partition):

============  =====================  ===========================================
input         terms                  breakpoints (membership 1 at)
============  =====================  ===========================================
e = |Δ|/π     small, medium, large   0, 0.5, 1      (0°, 90°, 180° off the sub-goal)
s             slow, medium, fast     0, 0.5, 1      (slowest, mid, fastest feasible sample)
c (m)         close, safe, far       d_safe, (d_safe + d_clip)/2, d_clip  (0.3, 0.65, 1.0 m)
============  =====================  ===========================================

The speed input is V rescaled over the step's feasible samples (`jaxplan.dwa._core.window_speed`):
with V = v/v_max a robot at rest sees only "slow" samples and never starts.

**Rule base** (27 rules, every combination; AND is the product, so a rule fires with
μ_e·μ_s·μ_c). A term has a level — heading small 1, medium ½, large 0; speed slow 0,
medium ½, fast 1; clearance close 0, safe ½, far 1 — and a rule's consequent is the
weighted level ``z = (α·ℓ_e + β·ℓ_s + γ·ℓ_c)/(α + β + γ)``, cut to ``VETO·z`` (VETO = ½)
when the heading is large or the obstacle close. With (α, β, γ) = (0.4, 0.3, 0.3):

=========  ===========================  ===========================  ===========================
heading    clearance close (s/m/f)      clearance safe (s/m/f)       clearance far (s/m/f)
=========  ===========================  ===========================  ===========================
small      0.200 / 0.275 / 0.350        0.550 / 0.700 / 0.850        0.700 / 0.850 / 1.000
medium     0.100 / 0.175 / 0.250        0.350 / 0.500 / 0.650        0.500 / 0.650 / 0.800
large      0.000 / 0.075 / 0.150        0.075 / 0.150 / 0.225        0.150 / 0.225 / 0.300
=========  ===========================  ===========================  ===========================

("s/m/f" = speed slow / medium / fast.) The rule "small, fast, far" is the only one
rated 1 (high); every rule with a large heading or a close obstacle is cut to half
(low). Without the cut the rule base would reproduce exactly the weighted sum
(α·G + β·V + γ·O')/(α + β + γ) with O' = clip((c − d_safe)/(d_clip − d_safe), 0, 1)
(triangular Ruspini memberships with product AND interpolate the levels linearly), so
the cut is what makes the evaluation fuzzy rather than linear: rollouts that head away
from the sub-goal or graze obstacles lose half their rating.

**Defuzzification:** the weighted average Σ_r w_r·z_r / Σ_r w_r of the rules' firing
strengths w_r and consequents z_r. Because the consequents are functions of the
weights, the evaluation stays differentiable in (α, β, γ) for tuning.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxplan.dwa._config import DWAParams

__all__ = ["VETO", "HEADING_LEVELS", "SPEED_LEVELS", "CLEARANCE_LEVELS", "memberships", "input_memberships",
           "rule_table", "fuzzy_evaluate"]

VETO = 0.5
"""Factor applied to a rule's consequent when the heading is large or the obstacle close."""

HEADING_LEVELS = (1.0, 0.5, 0.0)  # small, medium, large
SPEED_LEVELS = (0.0, 0.5, 1.0)  # slow, medium, fast
CLEARANCE_LEVELS = (0.0, 0.5, 1.0)  # close, safe, far


def memberships(x: jnp.ndarray, lo, mid, hi) -> tuple[jnp.ndarray, jnp.ndarray, jnp.ndarray]:
    """Degrees (each shaped like ``x``) of a left shoulder (1 at ``lo``), a triangle (1 at ``mid``)
    and a right shoulder (1 at ``hi``); they sum to 1."""
    left = jnp.clip((mid - x) / (mid - lo), 0.0, 1.0)
    right = jnp.clip((x - mid) / (hi - mid), 0.0, 1.0)
    return left, 1.0 - left - right, right


def input_memberships(e: jnp.ndarray, s: jnp.ndarray, c: jnp.ndarray, d_safe, d_clip) -> tuple:
    """Degrees of the three inputs: heading (small, medium, large), speed (slow, medium, fast),
    clearance (close, safe, far); breakpoints in the module docstring."""
    return (memberships(e, 0.0, 0.5, 1.0), memberships(s, 0.0, 0.5, 1.0),
            memberships(c, d_safe, (d_safe + d_clip) / 2, d_clip))


def rule_table(params: DWAParams) -> jnp.ndarray:
    """``[3, 3, 3]`` consequents z[heading, speed, clearance] of the 27 rules (module docstring)."""
    lh = jnp.asarray(HEADING_LEVELS)[:, None, None]
    ls = jnp.asarray(SPEED_LEVELS)[None, :, None]
    lc = jnp.asarray(CLEARANCE_LEVELS)[None, None, :]
    total = params.heading + params.velocity + params.clearance
    z = (params.heading * lh + params.velocity * ls + params.clearance * lc) / jnp.maximum(total, 1e-12)
    veto = jnp.zeros((3, 3, 3), bool).at[2].set(True).at[:, :, 0].set(True)  # heading large or clearance close
    return jnp.where(veto, VETO * z, z)


def fuzzy_evaluate(e: jnp.ndarray, s: jnp.ndarray, c: jnp.ndarray, params: DWAParams, d_safe, d_clip) -> jnp.ndarray:
    """The defuzzified rating in [0, 1] of rollouts with heading deviation ``e = |Δ|/π``, speed ratio ``s``
    and minimum clearance ``c`` (m), all ``[S]``.

    The 27 rules are summed in an unrolled loop of elementwise terms rather than through a
    ``[3, 3, 3, S]`` tensor: XLA fuses it into a single kernel.
    """
    mh, ms, mc = input_memberships(e, s, c, d_safe, d_clip)
    z = rule_table(params)
    num = jnp.zeros_like(e)
    den = jnp.zeros_like(e)
    for h in range(3):
        for v in range(3):
            hv = mh[h] * ms[v]
            for k in range(3):
                w = hv * mc[k]  # firing strength of rule (h, v, k): product AND
                num = num + w * z[h, v, k]
                den = den + w
    return num / jnp.maximum(den, 1e-12)
