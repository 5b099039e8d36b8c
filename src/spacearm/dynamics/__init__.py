"""Free-floating dynamics written once for every robot (gravity zero, any momentum).

State: joints q ``(..., n)`` and rates qd ``(..., n)``, the bus attitude R (``base_rotation``,
bus axes -> inertial axes, default identity) and the system momentum m = [P; L]: the linear
momentum and the angular momentum about the system centroid, inertial axes (default zero,
the assumption of Umetani & Yoshida 1990, eq. 3-5). A planar robot passes its posture
phi = [phi0, q] instead of (q, R), and every 6-vector shrinks to its in-plane part
[x, y, rz] (the family's ``twist_axes``): momentum [Px, Py, L], base velocity [vx, vy, w].

Coordinates: nu = [v; w; qd], v the velocity of the bus centroid and w the bus angular
velocity, both in bus axes. With H the system mass matrix in these coordinates and c the
bias forces (`spacearm.models.dynamics`: one pass over the robot's tree, c by Newton-Euler
on it), the free-floating system under joint torques tau and a bus wrench
[f; n] (force at the bus centroid, torque about it, bus axes) is

    H nu' + c(q, nu) = [f; n; tau].

Partitioned as H = [[H_b, H_bm], [H_bm^T, H_m]], c = [c_b; c_m]:

- base velocity from the momentum: H_b [v; w] + H_bm qd = [R^T P; R^T L + (g - b) x R^T P]
  (g - b the system centroid about the bus centroid, bus axes), eq. 4-5 with any momentum;
- free bus (f = n = 0): H* qdd + c* = tau with the reduced inertia H* = H_m - H_bm^T H_b^-1 H_bm
  and the reduced bias c* = c_m - H_bm^T H_b^-1 c_b;
- tip twist J nu, J = [J_S, J_M] (SpaceDyn's calc_gj11 with its momentum term), and the
  extended inversed inertia tensor G = J H^-1 J^T (Yoshida): the tip's velocity jump per
  tip impulse; with the joints locked, G = J_S H_b^-1 J_S^T (one rigid body).
"""

from .equations import (
    BASE_MODES as BASE_MODES,
    arm_inertia as arm_inertia,
    bias_forces as bias_forces,
    forward_dynamics as forward_dynamics,
    free_motion as free_motion,
    inverse_dynamics as inverse_dynamics,
    joint_mass_matrix as joint_mass_matrix,
    mass_matrix as mass_matrix,
    reduced_bias as reduced_bias,
)
from .impacts import (
    JOINT_MODES as JOINT_MODES,
    bus_rate_jump as bus_rate_jump,
    capture as capture,
    impulse_response as impulse_response,
    tip_inverse_inertia as tip_inverse_inertia,
    virtual_mass as virtual_mass,
)
from .payload import (
    grasped_robot as grasped_robot,
    system_momentum as system_momentum,
    target_from_tip_frame as target_from_tip_frame,
    target_in_tip_frame as target_in_tip_frame,
)
from .state import DynamicState as DynamicState
from .velocities import base_velocity as base_velocity, tip_velocity as tip_velocity
from .wheels import wheel_momentum as wheel_momentum

__all__ = [
    "BASE_MODES",
    "JOINT_MODES",
    "DynamicState",
    "arm_inertia",
    "base_velocity",
    "bias_forces",
    "bus_rate_jump",
    "capture",
    "forward_dynamics",
    "free_motion",
    "grasped_robot",
    "impulse_response",
    "inverse_dynamics",
    "joint_mass_matrix",
    "mass_matrix",
    "reduced_bias",
    "system_momentum",
    "target_from_tip_frame",
    "target_in_tip_frame",
    "tip_inverse_inertia",
    "tip_velocity",
    "virtual_mass",
    "wheel_momentum",
]
