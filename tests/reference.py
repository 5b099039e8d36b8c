"""An independent, deliberately naive NumPy model of the free-floating planar arm.

Built from the geometry of Fig. 1 directly (walk the chain, subtract the mass
centre) and from finite differences, sharing no code with spacearm, so tests can
hold the package's closed forms against it.
"""

from __future__ import annotations

import numpy as np


def design(robot):
    """Plain floats and lists from a single-design PlanarRobot."""
    return dict(
        m=[float(robot.base_mass)] + [float(x) for x in np.asarray(robot.link_mass)],
        inertia=[float(robot.base_inertia)] + [float(x) for x in np.asarray(robot.link_inertia)],
        b0=float(robot.base_attach),
        a=[float(x) for x in np.asarray(robot.link_a)],
        b=[float(x) for x in np.asarray(robot.link_b)],
    )


def bodies_and_tip(d, phi):
    """Centroids of bodies 0..n and the tip, inertial frame, origin at the system centroid."""
    phi = np.asarray(phi)
    theta = np.cumsum(phi)
    unit = lambda t: np.array([np.cos(t), np.sin(t)])
    centroids = [np.zeros(2, dtype=theta.dtype)]
    joint = centroids[0] + d["b0"] * unit(theta[0])
    for i in range(len(d["a"])):
        centroids.append(joint + d["a"][i] * unit(theta[i + 1]))
        joint = joint + (d["a"][i] + d["b"][i]) * unit(theta[i + 1])
    centroids = np.array(centroids)
    com = np.sum(np.array(d["m"])[:, None] * centroids, axis=0) / sum(d["m"])
    return centroids - com, joint - com


def tip(d, phi):
    return bodies_and_tip(d, phi)[1]


def momentum(d, phi, phi_rates, h=1e-30):
    """Linear (2,) and angular momentum about the system centroid.

    Velocities by the complex step, Im r(phi + i h dphi) / h, exact to rounding.
    """
    phi, phi_rates = np.asarray(phi, float), np.asarray(phi_rates, float)
    r_step, _ = bodies_and_tip(d, phi + 1j * h * phi_rates)
    r, _ = bodies_and_tip(d, phi)
    v = r_step.imag / h
    theta_rates = np.cumsum(phi_rates)
    m = np.array(d["m"])
    linear = np.sum(m[:, None] * v, axis=0)
    angular = sum(
        d["inertia"][i] * theta_rates[i] + m[i] * (r[i, 0] * v[i, 1] - r[i, 1] * v[i, 0]) for i in range(len(m))
    )
    return linear, angular


def base_rate(d, phi, joint_rates):
    """dphi0 that zeroes the angular momentum (momentum is linear in the rates)."""
    n = len(d["a"])
    _, per_base = momentum(d, phi, np.r_[1.0, np.zeros(n)])
    _, per_joints = momentum(d, phi, np.r_[0.0, joint_rates])
    return -per_joints / per_base


def generalized_jacobian(d, phi, h=1e-30):
    """J* column by column: move one joint at unit rate, the base following, differentiate the
    tip (complex step)."""
    n = len(d["a"])
    phi = np.asarray(phi, float)
    columns = []
    for j in range(n):
        rates = np.zeros(n)
        rates[j] = 1.0
        direction = np.r_[base_rate(d, phi, rates), rates]
        columns.append(tip(d, phi + 1j * h * direction).imag / h)
    return np.array(columns).T
