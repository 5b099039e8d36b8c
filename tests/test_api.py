"""The curated top-level API: every ``sa.*`` name serves every family or refuses the other.

The family-independent kernels must give the same numbers through ``sa`` for both
families (checked against the family's own primitives elsewhere); here the contract is
the shape of the namespace: ``__all__`` resolves, the planar closed forms kept under
their old names refuse a spatial arm with a TypeError naming the function (instead of an
AttributeError deep inside a trace), and the spatial-only kernels refuse a planar arm.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import pytest

import spacearm as sa
from spacearm import inertia

# Planar closed forms kept at the top level: (name, arguments after the robot).
PLANAR_ONLY = {
    "angular_momentum": lambda q: (q, q),
    "arm_jacobian": lambda q: (q,),
    "base_jacobian": lambda q: (q,),
    "centroid_positions": lambda q: (q,),
    "design_coefficients": lambda q: (),
    "manipulability_ellipse": lambda q: (q,),
    "manipulability_on_grid": lambda q: ([jnp.zeros(3)] * 6,),
    "momentum_inertias": lambda q: (q,),
    "robot_frame_tip_position": lambda q: (q,),
    "tip_coefficients": lambda q: (),
    "normalized_areas": lambda q: (),
    "maximum_reachable_radii": lambda q: (),
    "straight_path_workspace": lambda q: (q, 4),
    "go_and_back": lambda q: (q, jnp.array([1.0, 0.0, 0.0]), 0.01),
    "straight_tip_path_history": lambda q: (q, jnp.array([1.0, 0.0, 0.0])),
}

ROTATIONAL_ROWS = [
    "base_twist_map",
    "dynamic_manipulability",
    "fixed_base_ellipsoid",
    "rotational_ellipsoid",
    "rotational_manipulability",
]


@pytest.fixture(scope="module")
def ur5():
    return sa.load_robot("configs/ur5-smallsat.yaml")


def test_every_public_name_resolves_and_dir_lists_only_them():
    assert len(sa.__all__) == len(set(sa.__all__))
    for name in sa.__all__:
        assert getattr(sa, name) is not None, name
    assert sorted(dir(sa)) == sorted(sa.__all__)


@pytest.mark.parametrize("name", sorted(PLANAR_ONLY))
def test_planar_only_names_refuse_a_spatial_arm_by_name(name, ur5):
    function = getattr(sa, name)
    assert "Planar arms only" in function.__doc__
    q = jnp.zeros(ur5.n_joints)
    with pytest.raises(TypeError, match=rf"^{name}: planar arms only, got a SpatialRobot"):
        function(ur5, *PLANAR_ONLY[name](q))


@pytest.mark.parametrize("name", ROTATIONAL_ROWS)
def test_kernels_of_the_rotational_rows_refuse_a_planar_arm_by_name(name, table1):
    with pytest.raises(TypeError, match=rf"^{name}: the tip twist has no rotational rows for a planar robot"):
        getattr(inertia, name)(table1, jnp.zeros(3))


def test_planar_workspaces_outside_the_top_level_refuse_a_spatial_arm(ur5):
    for name in ("guaranteed_radius", "attitude_constraint", "fixed_vehicle_radius", "dynamic_singularities"):
        with pytest.raises(TypeError, match=rf"^{name}: planar arms only"):
            getattr(sa.paper, name)(ur5)


def test_the_guard_changes_no_planar_number(table1):
    # Table 1 arm at phi = 0: K0 + K1 + K2 and the stretched J_M against their closed forms
    K = np.asarray(sa.tip_coefficients(table1))
    assert float(sa.maximum_reachable_radius(table1)) == pytest.approx(K.sum(), rel=1e-15)
    J_M = np.asarray(sa.arm_jacobian(table1, jnp.zeros(3)))
    np.testing.assert_allclose(J_M[0], 0.0, atol=1e-15)  # the stretched arm along x: no x velocity
    np.testing.assert_allclose(J_M[1], [K[1] + K[2], K[2]], rtol=1e-14)


def test_stack_robots_serves_both_families(table1, ur5):
    assert type(sa.stack_robots([table1, table1])) is sa.PlanarRobot
    stacked = sa.stack_robots([ur5, ur5])
    assert type(stacked) is sa.SpatialRobot
    np.testing.assert_array_equal(np.asarray(stacked.base_mass), [ur5.base_mass] * 2)
