"""The lane integrator's end events on small closed-form fields (spacearm.motion.lanes)."""

import functools

import jax
import jax.numpy as jnp
import numpy as np

from spacearm.motion import REASON_JOINT_LIMIT, REASON_MAX_LENGTH, REASON_SINGULAR
from spacearm.motion.lanes import start_lane, step_lane

# y = [q1, q2, s]: joint 1 turns at unit speed towards its upper limit, joint 2 stays.
LOWER = np.array([-10.0, -10.0])


def _rate_field(rate0, decay):
    """ds/dsigma = rate0 - decay q1 (zero at q1 = rate0 / decay)."""
    return lambda y: jnp.stack([jnp.ones_like(y[0]), jnp.zeros_like(y[0]), rate0 - decay * y[0]])


@functools.partial(jax.jit, static_argnames=("decay_is_zero",))
def _run(rate0, decay, upper1, max_length, sing_rate, tip_tol, decay_is_zero=False):
    """One redundant (non-square) path from q = 0 to its end: (y, steps, reason)."""
    field = _rate_field(rate0, 0.0 if decay_is_zero else decay)
    lane = start_lane(field, jnp.zeros(3), 0.1, {})
    upper = jnp.stack([upper1, 10.0])
    step = functools.partial(
        step_lane,
        field,
        joints=(0, 2),
        lower=jnp.asarray(LOWER),
        upper=upper,
        square=False,
        max_length=max_length,
        max_step=0.1,
        tol=1e-11,
        rtol=1e-12,
        sing_rate=sing_rate,
        max_steps=2000,
        tip_tol=tip_tol,
    )

    def body(state):
        lane, _, _ = state
        return step(lane)

    lane, _, reason = jax.lax.while_loop(lambda s: ~s[1], body, (lane, jnp.bool_(False), jnp.int32(-1)))
    return lane["y"], lane["count"], reason


def test_a_flat_rate_ends_once_its_travel_to_the_joint_limit_is_below_tip_tol():
    # 1e-4 m/rad with the limit 5 rad away: 5e-4 m left, below 1e-3 m: the first step ends it.
    y, steps, reason = _run(1e-4, 0.0, 5.0, jnp.inf, 1e-6, 1e-3, decay_is_zero=True)
    assert int(reason) == REASON_SINGULAR and int(steps) == 0
    assert float(y[-1]) == 0.0
    # 20 rad away (2e-3 m left): the path runs until the travel left is 1e-3 m, within a step.
    y, steps, reason = _run(1e-4, 0.0, 20.0, jnp.inf, 1e-6, 1e-3, decay_is_zero=True)
    assert int(reason) == REASON_SINGULAR
    assert 10.0 <= float(y[0]) <= 10.1 + 1e-12
    np.testing.assert_allclose(float(y[-1]), 1e-4 * float(y[0]), rtol=1e-12)  # s = rate * q1 exactly
    # the end falls short of the exact one (the limit, s = 2e-3 m) by at most tip_tol
    assert 0.0 < 2e-3 - float(y[-1]) <= 1e-3
    # without the travel rule the same path ends at the joint limit, located to tol
    y, _, reason = _run(1e-4, 0.0, 20.0, jnp.inf, 1e-6, -jnp.inf, decay_is_zero=True)
    assert int(reason) == REASON_JOINT_LIMIT
    assert abs(float(y[0]) - 20.0) < 1e-10


def test_a_rate_that_reaches_zero_before_the_limit_is_located_not_stalled():
    # ds/dsigma = 0.3 - 0.3 q1 vanishes at q1 = 1 (the limit is at 5): a one-sided approach,
    # located to tol in joint arc; its travel (0.15 m) is far above tip_tol anyway, so the
    # test also sets a huge tip_tol: the rule must not fire while the rate decays to zero
    # before the limit.
    y, _, reason = _run(0.3, 0.3, 5.0, jnp.inf, -jnp.inf, 1.0)
    assert int(reason) == REASON_SINGULAR
    assert abs(float(y[0]) - 1.0) < 1e-10
    np.testing.assert_allclose(float(y[-1]), 0.15, atol=1e-12)


def test_a_length_event_before_the_limit_is_not_a_stall():
    # flat 1e-4 m/rad, limit 5 rad away (5e-4 m), but max_length = 2e-4 m comes first
    y, _, reason = _run(1e-4, 0.0, 5.0, 2e-4, 1e-6, 1e-3, decay_is_zero=True)
    assert int(reason) == REASON_MAX_LENGTH
    np.testing.assert_allclose(float(y[-1]), 2e-4, atol=1e-14)
