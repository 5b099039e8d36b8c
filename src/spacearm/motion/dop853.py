"""The 8th-order Runge-Kutta method of Dormand & Prince (DOP853): tableau, step, error.

The 12-stage, 8th-order solution weights of Hairer, Norsett & Wanner, "Solving Ordinary
Differential Equations I", 2nd ed., section II.10 (the coefficients of Hairer's DOP853 code,
as also used by SciPy), with the embedded 5th- and 3rd-order error estimators. No
dense output. Generated once from SciPy's table; kept literal so the package needs no SciPy.
"""

import jax
import jax.numpy as jnp
import numpy as np

from .._core.errors import ConfigError

__all__ = ["SOLUTION_WEIGHTS", "STAGE_TIMES", "STAGE_WEIGHTS", "error_norm", "rk_step", "tableau_arrays"]

STAGE_TIMES = (
    0.0,
    0.05260015195876773,
    0.0789002279381516,
    0.1183503419072274,
    0.2816496580927726,
    0.3333333333333333,
    0.25,
    0.3076923076923077,
    0.6512820512820513,
    0.6,
    0.8571428571428571,
    1.0,
)

# Row i holds a_ij for j < i (strictly lower triangular).
STAGE_WEIGHTS = (
    (),
    (0.05260015195876773,),
    (0.0197250569845379, 0.0591751709536137),
    (0.02958758547680685, 0.0, 0.08876275643042054),
    (0.2413651341592667, 0.0, -0.8845494793282861, 0.924834003261792),
    (0.037037037037037035, 0.0, 0.0, 0.17082860872947386, 0.12546768756682242),
    (0.037109375, 0.0, 0.0, 0.17025221101954405, 0.06021653898045596, -0.017578125),
    (
        0.03709200011850479,
        0.0,
        0.0,
        0.17038392571223998,
        0.10726203044637328,
        -0.015319437748624402,
        0.008273789163814023,
    ),
    (
        0.6241109587160757,
        0.0,
        0.0,
        -3.3608926294469414,
        -0.868219346841726,
        27.59209969944671,
        20.154067550477894,
        -43.48988418106996,
    ),
    (
        0.47766253643826434,
        0.0,
        0.0,
        -2.4881146199716677,
        -0.590290826836843,
        21.230051448181193,
        15.279233632882423,
        -33.28821096898486,
        -0.020331201708508627,
    ),
    (
        -0.9371424300859873,
        0.0,
        0.0,
        5.186372428844064,
        1.0914373489967295,
        -8.149787010746927,
        -18.52006565999696,
        22.739487099350505,
        2.4936055526796523,
        -3.0467644718982196,
    ),
    (
        2.273310147516538,
        0.0,
        0.0,
        -10.53449546673725,
        -2.0008720582248625,
        -17.9589318631188,
        27.94888452941996,
        -2.8589982771350235,
        -8.87285693353063,
        12.360567175794303,
        0.6433927460157636,
    ),
)

SOLUTION_WEIGHTS = (
    0.054293734116568765,
    0.0,
    0.0,
    0.0,
    0.0,
    4.450312892752409,
    1.8915178993145003,
    -5.801203960010585,
    0.3111643669578199,
    -0.1521609496625161,
    0.20136540080403034,
    0.04471061572777259,
)

# Embedded error estimators (weights on the 12 stages and f(y_new)): 5th and 3rd order;
# the error norm combines them as in Hairer's DOP853 (and scipy.integrate.DOP853).
ERROR_WEIGHTS_5 = (
    0.01312004499419488,
    0.0,
    0.0,
    0.0,
    0.0,
    -1.2251564463762044,
    -0.4957589496572502,
    1.6643771824549864,
    -0.35032884874997366,
    0.3341791187130175,
    0.08192320648511571,
    -0.022355307863886294,
    0.0,
)
ERROR_WEIGHTS_3 = (
    -0.18980075407240762,
    0.0,
    0.0,
    0.0,
    0.0,
    4.450312892752409,
    1.8915178993145003,
    -5.801203960010585,
    -0.4226823213237919,
    -0.1521609496625161,
    0.20136540080403034,
    0.02265179219836082,
    0.0,
)


def tableau_arrays(tableau: str):
    """(stage weights (S, S) lower triangular, solution weights (S,)) as NumPy arrays."""
    if tableau == "rk4":
        a = np.array([[0, 0, 0, 0], [0.5, 0, 0, 0], [0, 0.5, 0, 0], [0, 0, 1.0, 0]])
        return a, np.array([1.0, 2.0, 2.0, 1.0]) / 6.0
    if tableau == "dop853":
        stages = len(STAGE_WEIGHTS)
        a = np.zeros((stages, stages))
        for i, row in enumerate(STAGE_WEIGHTS):
            a[i, : len(row)] = row
        return a, np.asarray(SOLUTION_WEIGHTS)
    raise ConfigError(f"tableau: unknown scheme {tableau!r}; use 'dop853' or 'rk4'")


def rk_step(
    field, y, h, tableau="dop853", return_slopes=False, *, rolled=False, first_slope=None, end_slope=False, aux=None
):
    """One explicit Runge-Kutta step of size h (may be negative) of y' = field(y).

    Unrolled (default), the stages are written out at trace time: under vmap on CPU this
    runs several times faster than a loop over the stages for a cheap closed-form field,
    at the price of a longer compile (benchmarks/bench_motion.py). ``rolled``
    runs the stages in a ``lax.fori_loop`` over a stage array: one copy of the field in
    the program, for fields that hold a loop themselves (a scan over a kinematic chain),
    where unrolling multiplies the compile time and buys no speed.

    Args:
        first_slope: field(y) when the caller knows it (the first stage is not evaluated).
        end_slope: rolled only: also evaluate field(y_new) inside the same loop, as a 13th
            stage whose weights are the solution weights (one copy of the field in the
            program instead of two); it is the last row of the returned slopes.
        aux: rolled only: ``field`` returns ``(slope, aux vector)`` and this is the zero aux
            vector ``(p,)``; the step also returns each stage's aux ``(stages, p)`` (zero
            where a stage is not evaluated): what the field's evaluation computes besides
            the slope, kept without a second copy of the field.

    Returns:
        y_new, or (y_new, slopes) with ``return_slopes``: a list of the stage slopes
        (unrolled) or a ``(stages, m)`` array (rolled).
    """
    a, b = tableau_arrays(tableau)
    if rolled:
        stages = a.shape[0]
        if end_slope:  # one more row: the solution weights, i.e. the slope at y_new
            a = np.vstack([np.hstack([a, np.zeros((stages, 1))]), np.append(b, 0.0)[None]])
            b = np.append(b, 0.0)
            stages += 1
        A = jnp.asarray(a, y.dtype)
        K = jnp.zeros((stages,) + y.shape, y.dtype)
        if first_slope is None:
            first = 0
        else:
            first = 1
            K = K.at[0].set(first_slope)
        if aux is not None:

            def stage(i, carry):
                K, X = carry
                k, x = field(y + h * (A[i] @ K))
                return K.at[i].set(k), X.at[i].set(x)

            X = jnp.zeros((stages,) + aux.shape, aux.dtype)
            K, X = jax.lax.fori_loop(first, stages, stage, (K, X))
            y_new = y + h * (jnp.asarray(b, y.dtype) @ K)
            return (y_new, K, X) if return_slopes else (y_new, X)
        K = jax.lax.fori_loop(first, stages, lambda i, K: K.at[i].set(field(y + h * (A[i] @ K))), K)
        y_new = y + h * (jnp.asarray(b, y.dtype) @ K)
        return (y_new, K) if return_slopes else y_new
    slopes = []
    for i, row in enumerate(a):
        if i == 0 and first_slope is not None:
            slopes.append(first_slope)
            continue
        increment = sum((w * k for w, k in zip(row, slopes, strict=False) if w != 0.0), jnp.zeros_like(y))
        slopes.append(field(y + h * increment))
    y_new = y + h * sum(w * k for w, k in zip(b, slopes, strict=False) if w != 0.0)
    return (y_new, slopes) if return_slopes else y_new


def error_norm(h, slopes, slope_new, y, y_new, rtol):
    """Hairer's DOP853 error norm of one step (<= 1: accept), from the stage slopes
    (a list, or a ``(12, m)`` or ``(13, m)`` array from a rolled step; with 13 rows the
    last is the slope at y_new)."""
    scale = rtol * (1.0 + jnp.maximum(jnp.abs(y), jnp.abs(y_new)))
    if isinstance(slopes, (list, tuple)):
        every = list(slopes) + [slope_new]  # 13 slopes (m,)
        err5 = sum(w * k for w, k in zip(ERROR_WEIGHTS_5, every, strict=False) if w != 0.0) / scale
        err3 = sum(w * k for w, k in zip(ERROR_WEIGHTS_3, every, strict=False) if w != 0.0) / scale
    else:  # the last weights (on slope_new) are zero
        rows = slopes.shape[0]
        err5 = (jnp.asarray(ERROR_WEIGHTS_5[:rows], y.dtype) @ slopes) / scale
        err3 = (jnp.asarray(ERROR_WEIGHTS_3[:rows], y.dtype) @ slopes) / scale
    e5, e3 = jnp.sum(err5**2), jnp.sum(err3**2)
    denom = e5 + 0.01 * e3
    safe = jnp.where(denom > 0, denom, 1.0)
    return jnp.where(denom > 0, jnp.abs(h) * e5 / jnp.sqrt(safe * y.shape[0]), 0.0)
