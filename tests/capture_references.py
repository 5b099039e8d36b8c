"""Independent references for a grasp and for the reaction-wheel momentum: Pinocchio.

The capture reference models the grasp as what it is physically: the target is a second
free-floating rigid body (a free-flyer joint added to the robot's Pinocchio model, its frame
at the target centroid, world-aligned), and the grasp welds it to the tip frame: a 6D rigid
constraint between the tip frame and the target's frame placed at the tip, resolved by
``pinocchio.impulseDynamics`` with restitution 0 (a perfectly plastic impact). Pinocchio
solves the contact KKT system [M J_c^T; J_c 0] of the whole model; it never sees our
formula (Yoshida's extended inversed inertia tensor, Yoshida & Nenchev 1995). The
constraint's Jacobian (``RigidConstraintModel.jacobian``: J_c = J_1 - J_2, rows in the tip
frame's axes) goes to the Jacobian form of ``impulseDynamics``: the contact-model form
(Pinocchio 4.1) leaves the second joint's velocity out of the velocity it cancels, so a
moving target would be caught as if at rest (two free bodies, the second moving at 1 m/s
into the first at rest: no impulse).

With the joints locked, the robot is one rigid body: ``pinocchio.buildReducedModel`` locks
every arm joint at q. The joints keep moving at qd through the impact, which the rigid
reduced model cannot carry; only the relative twist of target and tip enters the impulse, so
the target's twist is taken relative to the tip body's motion from the joints (J_M qd, from
the full model), and the reduced model's bus velocity after the impact is the bus velocity.

The wheel momentum reference follows its definition: the bus held in attitude (w = 0) and
translating so that the system's linear momentum is P (solved with Pinocchio's centroidal
map), the bodies' angular momentum about the system centroid L_bodies from the same map, and
h = R^T (L - L_bodies), bus axes.

Conventions are those of `tests.dynamics_references` (Pinocchio's free-flyer velocity is
LOCAL at the bus origin, nu_ours = T nu_pin).
"""

from __future__ import annotations

import numpy as np

from .dynamics_references import PinocchioSystem


def _rotate6(R, x):
    return np.concatenate([R @ x[:3], R @ x[3:]])


def random_inertia(rng, mass):
    """A random SPD inertia (3, 3) about the centroid: a box of random sides, turned."""
    sides = rng.uniform(0.2, 2.0, 3)
    principal = mass / 12.0 * (np.sum(sides**2) - sides**2)
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    R = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
    return R @ np.diag(principal) @ R.T


class PinocchioCapture:
    """Capture and wheel momentum from Pinocchio, in our conventions (module docstring).

    Args:
        system: the robot's `PinocchioSystem` (its model, joint order and conversions).
    """

    def __init__(self, system: PinocchioSystem):
        import pinocchio as pin

        self.pin, self.system = pin, system
        self.model, self.data = system.model, system.data
        self.n, self.keep = system.n, system.keep
        self.tip_names = [system.model.frames[f].name for f in system.tips]

    # The state before ------------------------------------------------------------------------

    def velocity(self, q, qd, R, momentum):
        """nu_pin (our order) of the robot with joint rates qd and system momentum ``momentum``
        (kept components, inertial axes, L about the system centroid): the centroidal map."""
        system, pin = self.system, self.pin
        A = np.asarray(pin.computeCentroidalMap(self.model, self.data, system.config(q, R)))[:, system.order]
        base = np.linalg.solve(A[:, :6], system.embed(momentum) - A[:, 6:] @ qd)
        return np.concatenate([base, qd])

    def wheel_momentum(self, q, qd, R, momentum):
        """h (3,) bus axes (planar: the z entry): L - L_bodies with the bus at [v; 0], v from P."""
        system, pin = self.system, self.pin
        A = np.asarray(pin.computeCentroidalMap(self.model, self.data, system.config(q, R)))[:, system.order]
        total = system.embed(momentum)
        v = np.linalg.solve(A[:3, :3], total[:3] - A[:3, 6:] @ qd)
        bodies = A[3:] @ np.concatenate([v, np.zeros(3), qd])
        h = R.T @ (total[3:] - bodies)
        return h[2] if len(self.keep) == 3 else h

    def momentum_about_origin(self, q, R, nu_pin):
        """[P; L about the world origin] (6,), world axes, of the robot (bus origin at the origin)."""
        pin, system = self.pin, self.system
        config = system.config(q, R)
        pin.computeCentroidalMomentum(self.model, self.data, config, system._pin(nu_pin))
        hg = self.data.hg
        P, L = np.array(hg.linear), np.array(hg.angular)
        return np.concatenate([P, L + np.cross(np.array(self.data.com[0]), P)])

    def tip_motion(self, q, R, nu_pin, tip):
        """(origin (3,), twist [v of the tip origin; w] (6,)) of tip frame ``tip``, world axes."""
        pin, system = self.pin, self.system
        config = system.config(q, R)
        frame = system.tips[tip]
        pin.forwardKinematics(self.model, self.data, config, system._pin(nu_pin))
        pin.updateFramePlacements(self.model, self.data)
        twist = pin.getFrameVelocity(self.model, self.data, frame, pin.LOCAL_WORLD_ALIGNED)
        origin = np.array(self.data.oMf[frame].translation)
        return origin, np.concatenate([np.array(twist.linear), np.array(twist.angular)])

    def ours_to_pin(self, R, base_after, qd_after):
        """Our output (base [v of the bus centroid; w] kept components, inertial) -> nu_pin."""
        base = self.system.embed(base_after)
        bus = np.concatenate([R.T @ base[:3], R.T @ base[3:]])
        return self.system.Ti @ np.concatenate([bus, qd_after])

    # The grasp -------------------------------------------------------------------------------

    def capture(self, q, qd, R, momentum, target, tip=0, joints="free"):
        """Pinocchio's impulse dynamics of the grasp: qd_after (n,), base_after (kept, inertial),
        the impulse on the tip [linear; angular about the tip origin] (kept, inertial) and the
        robot's velocity after, nu_pin (6 + n,) in our order."""
        pin, system = self.pin, self.system
        nu = self.velocity(q, qd, R, momentum)
        config = system.config(q, R)
        velocity = np.asarray(target["velocity"], float)  # [v of the centroid; w], world axes
        if joints == "locked":
            _, moving = self.tip_motion(q, R, np.concatenate([np.zeros(6), qd]), tip)
            offset = np.asarray(target["offset"], float)
            relative = velocity - np.concatenate([moving[:3] + np.cross(moving[3:], offset), moving[3:]])
            arm = list(range(2, system.model.njoints))  # every joint below the free flyer (1)
            model = pin.buildReducedModel(system.model, arm, config)
            robot_config, robot_velocity = config[:7], nu[:6]
        else:
            relative, model = velocity, system.model
            robot_config, robot_velocity = config, system._pin(nu)
        after, impulse = self._weld(model, robot_config, robot_velocity, target, relative, self.tip_names[tip])
        nu_after = np.concatenate([after[:6], qd]) if joints == "locked" else system._ours(after[: model.nv])
        base = _rotate6(R, (system.T @ nu_after)[:6])
        return nu_after[6:], base[self.keep], impulse[self.keep], nu_after

    def _weld(self, robot_model, robot_config, robot_velocity, target, velocity, tip_name):
        """impulseDynamics of ``robot_model`` plus the target (a free body moving at ``velocity``)
        welded to the frame ``tip_name``: (the robot's velocity after, the impulse on the tip
        frame [linear; angular about its origin], world axes)."""
        pin = self.pin
        model = pin.Model(robot_model)
        body = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "target")
        inertia = np.asarray(target["inertia"], float)
        model.appendBodyToJoint(body, pin.Inertia(float(target["mass"]), np.zeros(3), inertia), pin.SE3.Identity())
        data = model.createData()
        frame = model.frames[model.getFrameId(tip_name)]
        pin.framesForwardKinematics(model, data, np.r_[robot_config, np.zeros(7)])
        tip = data.oMf[model.getFrameId(tip_name)].copy()
        centroid = tip.translation + np.asarray(target["offset"], float)
        config = np.r_[robot_config, centroid, 0.0, 0.0, 0.0, 1.0]
        # The target's weld frame: the tip frame, seen from the target's (world-aligned) frame.
        weld = pin.SE3(tip.rotation, tip.translation - centroid)
        contact = pin.RigidConstraintModel(
            pin.ContactType.CONTACT_6D, model, frame.parentJoint, frame.placement, body, weld, pin.LOCAL
        )
        pin.computeJointJacobians(model, data, config)
        contact_data = contact.createData()
        contact.calc(model, data, contact_data)
        J = contact.jacobian(model, data, contact_data)  # J_1 - J_2, rows in the tip frame's axes
        v = np.r_[robot_velocity, velocity]
        after = pin.impulseDynamics(model, data, config, v, J, 0.0, 0.0)
        local = np.array(data.impulse_c)
        return np.array(after), _rotate6(tip.rotation, local)
