"""Spatial kernels: the planar bridge, physical invariants, the seam, and the pytree under jit/vmap/grad."""

import math
import os

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import spacearm as sa
from spacearm import inertia, kinematics
from spacearm.models import spatial
from spacearm.models.spatial import primitives
from spacearm.models.tree import primitives as tree_primitives
from spacearm.models.tree.algebra import BLOCK

from .spatial_references import config_urdf, random_rotation

CONFIGS = os.path.join(os.path.dirname(__file__), "..", "configs")


def _load(name):
    return sa.load_robot(os.path.join(CONFIGS, f"{name}.yaml"))


@pytest.fixture(scope="module")
def ur5():
    return _load("ur5-smallsat")


# The planar bridge ----------------------------------------------------------------------


def test_table1_urdf_reproduces_the_planar_generalized_jacobian():
    planar = _load("umetani1990")
    bridge = _load("umetani1990-spatial")
    rng = np.random.default_rng(0)
    q = rng.uniform(-math.pi, math.pi, (64, 2))
    phi = np.concatenate([np.zeros((64, 1)), q], axis=1)
    J = np.asarray(sa.generalized_jacobian(bridge, q))
    np.testing.assert_allclose(J[:, :2, :], sa.generalized_jacobian(planar, phi), rtol=0, atol=1e-12)
    # the motion stays in the plane: no v_z, no w_x, w_y
    np.testing.assert_allclose(J[:, [2, 3, 4], :], 0.0, atol=1e-12)
    np.testing.assert_allclose(np.asarray(sa.tip_position(bridge, q))[:, :2], sa.tip_position(planar, phi), atol=1e-12)
    w_planar = np.abs(J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0])
    np.testing.assert_allclose(w_planar, sa.manipulability(planar, phi), atol=1e-12)
    # the bus turns about z as the planar base does (eq. 5)
    C = np.asarray(sa.base_rate_matrix(bridge, q))
    np.testing.assert_allclose(C[:, 5, :], sa.base_rate_matrix(planar, phi)[:, 0, :], atol=1e-12)


# Invariants -----------------------------------------------------------------------------


def test_a_heavy_bus_gives_the_fixed_base_jacobian(ur5):
    rng = np.random.default_rng(1)
    q = rng.uniform(-3, 3, (8, 6))  # one batch shape (8, n) across the tests: compiled programs are reused
    heavy = ur5.replace(base_mass=np.float64(1e12), base_inertia=np.asarray(ur5.base_inertia) * 1e10)
    np.testing.assert_allclose(sa.generalized_jacobian(heavy, q), sa.fixed_base_jacobian(heavy, q), atol=1e-9)
    # and far from it for the real 500 kg bus
    assert np.max(np.abs(sa.generalized_jacobian(ur5, q) - sa.fixed_base_jacobian(ur5, q))) > 1e-2


def test_bus_attitude_rotates_twists_and_points(ur5):
    rng = np.random.default_rng(2)
    q = rng.uniform(-3, 3, (8, 6))
    R = np.stack([random_rotation(rng) for _ in range(8)])
    J_bus = np.asarray(sa.generalized_jacobian(ur5, q))
    J_inertial = np.asarray(sa.generalized_jacobian(ur5, q, base_rotation=R))
    expected = np.concatenate([R @ J_bus[:, :3], R @ J_bus[:, 3:]], axis=1)
    np.testing.assert_allclose(J_inertial, expected, atol=1e-14)
    np.testing.assert_allclose(
        sa.tip_position(ur5, q, base_rotation=R), np.einsum("bij,bj->bi", R, sa.tip_position(ur5, q)), atol=1e-14
    )
    # w* does not depend on the attitude
    J_v = J_inertial[:, :3]
    np.testing.assert_allclose(
        np.sqrt(np.linalg.det(J_v @ np.swapaxes(J_v, 1, 2))), sa.manipulability(ur5, q), rtol=1e-10
    )


def test_zero_momentum_holds_in_pinocchio(ur5):
    """Joint rates plus the bus twist from C(q) carry no centroidal momentum (Pinocchio)."""
    pin = pytest.importorskip("pinocchio")
    combined, com = config_urdf(os.path.join(CONFIGS, "ur5-smallsat.yaml"))
    model = pin.buildModelFromXML(combined, pin.JointModelFreeFlyer())
    data = model.createData()
    rng = np.random.default_rng(3)
    qs, all_rates = rng.uniform(-3, 3, (8, 6)), rng.normal(size=(8, 6))
    twists = np.asarray(sa.base_rate(ur5, qs, all_rates))  # [v of bus centroid; w], bus axes
    for joint_q, rates, twist in zip(qs, all_rates, twists, strict=False):
        v_origin = twist[:3] - np.cross(twist[3:], com)  # the free-flyer origin is the bus-frame origin
        config = pin.neutral(model)
        config[7:] = joint_q
        h = pin.computeCentroidalMomentum(model, data, config, np.concatenate([v_origin, twist[3:], rates]))
        np.testing.assert_allclose(h.vector, 0.0, atol=1e-11)


def test_reaction_null_space_turns_the_bus_not_at_all(ur5):
    q = np.random.default_rng(8).uniform(-3, 3, (8, 6))
    C_w = np.asarray(inertia.base_twist_map(ur5, q))[0, 3:]
    _, _, vt = np.linalg.svd(C_w)
    null = vt[3:]  # n - 3 = 3 directions
    np.testing.assert_allclose(C_w @ null.T, 0.0, atol=1e-14)


# The seam: closed forms equal the generic path ---------------------------------------------


@jax.jit
def _internal_paths(robot, q):
    """The generic paths and the one-pass primitives (J* and the tip from one chain pass, the
    fixed-base Jacobian and the tip from one), called on concrete arrays as one program: not
    one per operation, nor one per path."""
    return (
        kinematics.generic_generalized_jacobian(robot, q),
        kinematics.generic_tip_position(robot, q),
        kinematics.generic_manipulability(robot, q),
        primitives.tip_and_generalized_jacobian(robot, q),
        primitives.tip_and_fixed_base_jacobian(robot, q),
    )


@pytest.mark.slow
@pytest.mark.parametrize("name", ["ur5-smallsat", "arm3dof-100kg"])
def test_fast_paths_equal_the_generic_path(name):
    robot = _load(name)
    rng = np.random.default_rng(4)
    q = rng.uniform(-3, 3, (8, robot.n_joints))
    generic_J, generic_tip, generic_w, (J, tip), (fixed, tip_too) = _internal_paths(robot, q)
    np.testing.assert_allclose(generic_J, sa.generalized_jacobian(robot, q), atol=1e-13)
    np.testing.assert_allclose(generic_tip, sa.tip_position(robot, q), atol=1e-13)
    np.testing.assert_allclose(tip_too, tip, atol=1e-13)
    np.testing.assert_allclose(fixed, sa.fixed_base_jacobian(robot, q), atol=1e-13)
    np.testing.assert_allclose(generic_J, J, atol=1e-13)
    np.testing.assert_allclose(generic_tip, tip, atol=1e-13)
    np.testing.assert_allclose(generic_w, sa.manipulability(robot, q), atol=1e-12)
    rates = rng.normal(size=q.shape)
    np.testing.assert_allclose(
        jnp.einsum("bij,bj->bi", sa.base_rate_matrix(robot, q), rates), sa.base_rate(robot, q, rates), atol=1e-13
    )
    J_v = np.asarray(sa.fixed_base_jacobian(robot, q))[:, :3]
    gram = np.linalg.det(J_v @ np.swapaxes(J_v, 1, 2))
    np.testing.assert_allclose(sa.fixed_base_manipulability(robot, q), np.sqrt(np.maximum(gram, 0)), atol=1e-12)


@jax.jit
def _extra_metrics(robot, q, length):
    """The metrics beyond w* that test_metrics_extras reads, as one program (the jitted public
    kernels inlined unchanged: one compile instead of eight)."""
    return dict(
        w_rot=inertia.rotational_manipulability(robot, q),
        w_full=inertia.full_manipulability(robot, q, length),
        H=sa.arm_inertia(robot, q),
        M=sa.joint_mass_matrix(robot, q),
        w_dyn=inertia.dynamic_manipulability(robot, q),
        axes=sa.manipulability_ellipsoid(robot, q)[0],
        rot_axes=inertia.rotational_ellipsoid(robot, q)[0],
        fixed_axes=inertia.fixed_base_ellipsoid(robot, q)[0],
    )


def test_metrics_extras(ur5):
    rng = np.random.default_rng(5)
    q = rng.uniform(-3, 3, (8, 6))
    J = np.asarray(sa.generalized_jacobian(ur5, q))
    length = 0.8
    m = {name: np.asarray(value) for name, value in _extra_metrics(ur5, q, length).items()}
    w_rot = np.sqrt(np.linalg.det(J[:, 3:] @ np.swapaxes(J[:, 3:], 1, 2)))
    np.testing.assert_allclose(m["w_rot"], w_rot, rtol=1e-10)
    scaled = np.concatenate([J[:, :3] / length, J[:, 3:]], axis=1)
    np.testing.assert_allclose(m["w_full"], np.abs(np.linalg.det(scaled)), rtol=1e-9)
    H = m["H"]
    np.testing.assert_allclose(H, np.swapaxes(H, 1, 2), atol=1e-14)
    assert np.all(np.linalg.eigvalsh(H) > 0)
    assert np.all(np.linalg.eigvalsh(m["M"] - H) > -1e-12)  # a free bus only lightens the arm
    K = J[:, :3] @ np.linalg.inv(H)
    np.testing.assert_allclose(m["w_dyn"], np.sqrt(np.linalg.det(K @ np.swapaxes(K, 1, 2))), rtol=1e-9)
    np.testing.assert_allclose(np.prod(m["axes"], axis=-1), sa.manipulability(ur5, q), rtol=1e-10)
    np.testing.assert_allclose(np.prod(m["rot_axes"], axis=-1), w_rot, rtol=1e-10)
    np.testing.assert_allclose(np.prod(m["fixed_axes"], axis=-1), sa.fixed_base_manipulability(ur5, q), rtol=1e-10)


def test_any_leading_batch_shape(ur5):
    q = np.random.default_rng(6).uniform(-3, 3, (2, 3, 6))
    J = sa.generalized_jacobian(ur5, q)
    assert J.shape == (2, 3, 6, 6)
    np.testing.assert_allclose(J[1, 2], sa.generalized_jacobian(ur5, q.reshape(-1, 6)[:8])[5], atol=1e-15)
    assert sa.tip_position(ur5, q).shape == (2, 3, 3)
    assert sa.manipulability(ur5, q).shape == (2, 3)
    # more postures than one block: the blocked path agrees with single postures
    big = np.random.default_rng(7).uniform(-3, 3, (BLOCK + 5, 6))
    J_big = primitives.generalized_jacobian(ur5, big)
    for start in (0, BLOCK - 4):
        np.testing.assert_allclose(
            J_big[start : start + 8], sa.generalized_jacobian(ur5, big[start : start + 8]), atol=1e-15
        )


# The pytree -----------------------------------------------------------------------------


@pytest.mark.slow
def test_designs_batch_under_vmap_and_differentiate(ur5):
    designs = spatial.stack_spatial_robots(
        [
            ur5.replace(base_mass=np.float64(m), mount_xyz=np.array([0.6, 0.1, z]))
            for m, z in [(300.0, 0.4), (500.0, 0.5), (900.0, 0.7)]
        ]
    )
    assert designs.batch_shape == (3,)
    q = jnp.array([0.3, -1.1, 0.7, 0.2, -0.5, 1.3])
    w = jax.jit(jax.vmap(sa.manipulability, in_axes=(0, None)))(designs, q)
    for i, (m, z) in enumerate([(300.0, 0.4), (500.0, 0.5), (900.0, 0.7)]):
        single = ur5.replace(base_mass=np.float64(m), mount_xyz=np.array([0.6, 0.1, z]))
        np.testing.assert_allclose(w[i], sa.manipulability(single, q), rtol=1e-13)

    def objective(robot):
        return sa.manipulability(robot, q)

    grad = jax.grad(objective)(ur5)
    assert isinstance(grad, spatial.SpatialRobot)
    h = 1e-5
    for field, index in [("base_mass", ()), ("mount_xyz", (2,)), ("link_mass", (1,)), ("mount_rpy", (0,))]:
        value = np.array(getattr(ur5, field), dtype=float)
        up, down = value.copy(), value.copy()
        step = h * max(1.0, abs(float(value[index])))
        up[index] += step
        down[index] -= step
        numeric = (objective(ur5.replace(**{field: up})) - objective(ur5.replace(**{field: down}))) / (2 * step)
        np.testing.assert_allclose(np.asarray(getattr(grad, field))[index], numeric, rtol=1e-5, atol=1e-12)


def test_renaming_or_new_values_do_not_recompile(ur5):
    q = jnp.asarray(np.random.default_rng(9).uniform(-3, 3, (8, 6)))
    sa.generalized_jacobian(ur5, q)
    before = sa.generalized_jacobian._cache_size()
    renamed = ur5.rename("another name")
    assert renamed.name == "another name"
    np.testing.assert_array_equal(sa.generalized_jacobian(renamed, q), sa.generalized_jacobian(ur5, q))
    sa.generalized_jacobian(ur5.replace(base_mass=np.float64(750.0)), q + 0.1)
    assert sa.generalized_jacobian._cache_size() == before


def test_singular_posture_gives_zero_and_finite_gradients():
    robot = _load("arm3dof-100kg")  # straight up along the bus z axis: the waist moves nothing
    q = jnp.zeros(3)
    assert float(sa.manipulability(robot, q)) < 1e-12
    grad = jax.grad(lambda p: sa.manipulability(robot, p))(q)
    assert np.all(np.isfinite(grad))


def test_ets7_matches_the_bmsd_convention():
    """The URDF transcription of model_ETS7.m reproduces bmsd's calc_pos centroids."""
    robot = _load("ets7")

    def rpy2R(x, y, z):  # bmsd: X-Y-Z about moving axes, R = Rx Ry Rz
        rx = np.array([[1, 0, 0], [0, math.cos(x), -math.sin(x)], [0, math.sin(x), math.cos(x)]])
        ry = np.array([[math.cos(y), 0, math.sin(y)], [0, 1, 0], [-math.sin(y), 0, math.cos(y)]])
        rz = np.array([[math.cos(z), -math.sin(z), 0], [math.sin(z), math.cos(z), 0], [0, 0, 1]])
        return rx @ ry @ rz

    pi = math.pi
    t = [(-0.785, -0.295, 1), (0, 0.275, 0.175), (0.435, 0, 0), (0.315, 0, 0), (0, 0, -0.1335), (0, 0, 0.1385)]
    f = [(0, 0, 0.175), (0.435, 0, 0), (0.315, 0, 0.275), (0, 0, -0.1335), (0, 0, 0.1385), (0, 0, 0.266)]
    rpy = [(0, 0, 0), (-pi / 2, 0, -pi / 2), (0, 0, pi / 2), (0, 0, -pi / 2), (pi / 2, pi / 2, 0), (pi, pi / 2, 0)]
    q = np.array([0.3, -0.7, 1.1, 0.4, -0.9, 0.6])
    R, p = np.eye(3), np.zeros(3)  # base centroid frame = bus frame
    centroids = []
    for i in range(6):
        R_child = R @ rpy2R(rpy[i][0], rpy[i][1], rpy[i][2] + q[i])
        p = p + R @ np.array(t[i]) + R_child @ np.array(f[i])
        R = R_child
        centroids.append(p)
    hand = p + R @ np.array([0.0, 0.266, 0.0])
    system_centroid, _, tips = tree_primitives.joint_points(primitives.as_tree(robot), jnp.asarray(q))
    bus_centroid = np.asarray(system_centroid)
    # link centroids: rebuild them from the subtree moments is indirect; compare the system centroid and the tip
    masses = [35.01, 22.45, 21.89, 16.54, 26.0, 18.49]
    G = (sum(m * c for m, c in zip(masses, centroids, strict=False))) / (2552.0 + sum(masses))
    np.testing.assert_allclose(bus_centroid, G, atol=1e-13)
    np.testing.assert_allclose(np.asarray(tips[0]), hand, atol=1e-13)
