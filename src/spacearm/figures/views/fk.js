// spacearm forward kinematics for the browser (and node): no Python at view time.
// spacearmPose(model, posture, R) evaluates the tree model of spacearm.models.view_model (every
// robot: bodies joined by revolute or prismatic joints, hung from mount frames on a free bus,
// tips on bodies). The posture maps to the joints and the bus attitude as model.posture says:
// the joints from joint_offset on; with base_turn, the bus attitude is a turn by one posture
// entry about base_turn.axis (R ignored), else R, the bus attitude as 3 rows (identity when
// absent). Returns, in inertial axes about the system centroid, m:
// {joints: joint origins, bodies: body origins (slid along prismatic axes), tips, segments:
// [[a, b],..] links parent to joint, joint to body where it slid, body to tip; owner: the tip
// (arm) of each segment, -1 when shared; mounts: mount origins, mountAxes: their axes as rows
// of columns; bus: bus centroid, corners: the 8 bus-box corners}.
"use strict";
(function (root) {
  function mv(m, v) { return [m[0][0]*v[0]+m[0][1]*v[1]+m[0][2]*v[2], m[1][0]*v[0]+m[1][1]*v[1]+m[1][2]*v[2], m[2][0]*v[0]+m[2][1]*v[1]+m[2][2]*v[2]]; }
  function mm(a, b) { var c = [[0,0,0],[0,0,0],[0,0,0]]; for (var i=0;i<3;i++) for (var j=0;j<3;j++) c[i][j]=a[i][0]*b[0][j]+a[i][1]*b[1][j]+a[i][2]*b[2][j]; return c; }
  function add(a, b) { return [a[0]+b[0], a[1]+b[1], a[2]+b[2]]; }
  function sub(a, b) { return [a[0]-b[0], a[1]-b[1], a[2]-b[2]]; }
  function scale(s, a) { return [s*a[0], s*a[1], s*a[2]]; }
  // Rotation by angle t about the unit axis k (Rodrigues).
  function axisAngle(k, t) {
    var c = Math.cos(t), s = Math.sin(t), v = 1 - c, x = k[0], y = k[1], z = k[2];
    return [[c+x*x*v, x*y*v-z*s, x*z*v+y*s], [y*x*v+z*s, c+y*y*v, y*z*v-x*s], [z*x*v-y*s, z*y*v+x*s, c+z*z*v]];
  }
  var EYE = [[1,0,0],[0,1,0],[0,0,1]];
  // The bus attitude and the joint values a posture stands for.
  function split(m, posture, R) {
    var layout = m.posture, turn = layout.base_turn, n = m.joint_kinds.length;
    var q = posture.slice(layout.joint_offset, layout.joint_offset + n);
    return {q: q, R: turn ? axisAngle(turn.axis, posture[turn.index]) : (R || EYE)};
  }
  function spacearmPose(m, posture, attitude) {
    var s = split(m, posture, attitude), q = s.q, R = s.R, n = m.joint_kinds.length;
    var rots = [], bodies = [], joints = [], segments = [], owner = [];
    var mass = m.base_mass, moment = scale(m.base_mass, m.base_com);
    m.mount_xyz.forEach(function (xyz, r) {
      mass += m.root_mass[r];
      moment = add(moment, scale(m.root_mass[r], add(xyz, mv(m.mount_rotation[r], m.root_com[r]))));
    });
    for (var k = 0; k < n; k++) {
      var p = m.parents[k], rot = p < 0 ? m.mount_rotation[-1 - p] : rots[p], origin = p < 0 ? m.mount_xyz[-1 - p] : bodies[p];
      var jointOrigin = add(origin, mv(rot, m.joint_translation[k])), frame = mm(rot, m.joint_rotation[k]);
      joints.push(jointOrigin);
      segments.push([origin, jointOrigin]); owner.push(m.owner[k]);
      if (m.joint_kinds[k] === "prismatic") {
        rots.push(frame); bodies.push(add(jointOrigin, scale(q[k], mv(frame, m.joint_axis[k]))));
        segments.push([jointOrigin, bodies[k]]); owner.push(m.owner[k]);
      } else {
        rots.push(mm(frame, axisAngle(m.joint_axis[k], q[k]))); bodies.push(jointOrigin);
      }
      mass += m.link_mass[k];
      moment = add(moment, scale(m.link_mass[k], add(bodies[k], mv(rots[k], m.link_com[k]))));
    }
    var tips = m.tip_bodies.map(function (b, t) {
      var tip = add(bodies[b], mv(rots[b], m.tip_translation[t]));
      segments.push([bodies[b], tip]); owner.push(t);
      return tip;
    });
    var g = scale(1 / mass, moment), out = function (p) { return mv(R, sub(p, g)); };
    return {joints: joints.map(out), bodies: bodies.map(out), tips: tips.map(out), owner: owner,
            segments: segments.map(function (seg) { return [out(seg[0]), out(seg[1])]; }),
            mounts: m.mount_xyz.map(out), mountAxes: m.mount_rotation.map(function (a) { return mm(R, a); }),
            bus: out(m.base_com), corners: m.bus_corners.map(out)};
  }
  root.spacearmPose = spacearmPose;
  if (typeof module !== "undefined" && module.exports) module.exports = {spacearmPose: spacearmPose};
})(typeof window !== "undefined" ? window : globalThis);
