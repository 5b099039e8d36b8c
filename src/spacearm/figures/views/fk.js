// spacearm forward kinematics for the browser (and node): no Python at view time.
// spacearmPose(model, q, R) -> {joints: [[x,y,z],..] joint origins then the tip, bus: bus
// centre, corners: 8 bus-box corners, mount: the arm's root origin} in inertial axes about
// the system centroid, m. Spatial: q (n,) joint values (rad; m for prismatic joints), R the
// bus attitude as 3 rows (identity when absent). Planar: q = [phi0, phi1, .., phin] (base
// attitude then joints, rad; R ignored), drawn in the plane z = 0. Tree (several arms on one bus):
// {joints: body origins, tips: [[x,y,z],..], segments: [[a, b],..] links joint to joint,
// owner: the arm (tip) of each segment (-1 when shared), mounts: root origins, mountAxes: their
// axes as rows of columns, bus, corners}.
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
  function finish(points, mass, moment, bus, corners, mount, R) {
    var g = scale(1 / mass, moment);
    var out = function (p) { return mv(R, sub(p, g)); };
    return {joints: points.map(out), bus: out(bus), corners: corners.map(out), mount: out(mount)};
  }
  function spatial(m, q, R) {
    R = R || EYE;
    var rot = m.mount_rotation, origin = m.mount_xyz, points = [];
    var mass = m.base_mass + m.root_mass;
    var moment = add(scale(m.base_mass, m.base_com), scale(m.root_mass, add(origin, mv(rot, m.root_com))));
    for (var k = 0; k < m.joint_axis.length; k++) {
      var jointOrigin = add(origin, mv(rot, m.joint_translation[k]));
      var frame = mm(rot, m.joint_rotation[k]);
      points.push(jointOrigin);
      if (m.joint_kinds[k] === "prismatic") {
        rot = frame; origin = add(jointOrigin, scale(q[k], mv(frame, m.joint_axis[k])));
      } else {
        rot = mm(frame, axisAngle(m.joint_axis[k], q[k])); origin = jointOrigin;
      }
      mass += m.link_mass[k];
      moment = add(moment, scale(m.link_mass[k], add(origin, mv(rot, m.link_com[k]))));
    }
    points.push(add(origin, mv(rot, m.tip_translation)));
    return finish(points, mass, moment, m.base_com, m.bus_corners, m.mount_xyz, R);
  }
  function tree(m, q, R) {
    R = R || EYE;
    var n = m.joint_axis.length, rots = [], origins = [], joints = [], segments = [], owner = [];
    var mass = m.base_mass, moment = scale(m.base_mass, m.base_com);
    m.mount_xyz.forEach(function (xyz, r) {
      mass += m.root_mass[r];
      moment = add(moment, scale(m.root_mass[r], add(xyz, mv(m.mount_rotation[r], m.root_com[r]))));
    });
    for (var k = 0; k < n; k++) {
      var p = m.parents[k], rot = p < 0 ? m.mount_rotation[-1 - p] : rots[p], origin = p < 0 ? m.mount_xyz[-1 - p] : origins[p];
      var jointOrigin = add(origin, mv(rot, m.joint_translation[k])), frame = mm(rot, m.joint_rotation[k]);
      joints.push(jointOrigin);
      segments.push([origin, jointOrigin]); owner.push(m.owner[k]);
      if (m.joint_kinds[k] === "prismatic") {
        rots.push(frame); origins.push(add(jointOrigin, scale(q[k], mv(frame, m.joint_axis[k]))));
        segments.push([jointOrigin, origins[k]]); owner.push(m.owner[k]);
      } else {
        rots.push(mm(frame, axisAngle(m.joint_axis[k], q[k]))); origins.push(jointOrigin);
      }
      mass += m.link_mass[k];
      moment = add(moment, scale(m.link_mass[k], add(origins[k], mv(rots[k], m.link_com[k]))));
    }
    var tips = m.tip_bodies.map(function (b, t) {
      var tip = add(origins[b], mv(rots[b], m.tip_translation[t]));
      segments.push([origins[b], tip]); owner.push(t);
      return tip;
    });
    var g = scale(1 / mass, moment), out = function (p) { return mv(R, sub(p, g)); };
    return {joints: origins.map(out), tips: tips.map(out), owner: owner,
            segments: segments.map(function (s) { return [out(s[0]), out(s[1])]; }),
            mounts: m.mount_xyz.map(out), mountAxes: m.mount_rotation.map(function (a) { return mm(R, a); }),
            bus: out(m.base_com), corners: m.bus_corners.map(out)};
  }
  function planar(m, phi) {
    var theta = phi[0], u = [Math.cos(theta), Math.sin(theta), 0];
    var c = Math.cos(theta), s = Math.sin(theta), R = [[c,-s,0],[s,c,0],[0,0,1]];
    var joint = scale(m.attach, u), points = [joint], mass = m.base_mass, moment = [0, 0, 0];
    for (var i = 0; i < m.a.length; i++) {
      theta += phi[i + 1]; u = [Math.cos(theta), Math.sin(theta), 0];
      var centroid = add(joint, scale(m.a[i], u));
      joint = add(centroid, scale(m.b[i], u));
      points.push(joint);
      mass += m.link_mass[i]; moment = add(moment, scale(m.link_mass[i], centroid));
    }
    var corners = m.bus_corners.map(function (p) { return mv(R, p); });
    var g = scale(1 / mass, moment), out = function (p) { return sub(p, g); };
    return {joints: points.map(out), bus: out([0, 0, 0]), corners: corners.map(out), mount: out(points[0])};
  }
  function spacearmPose(model, q, R) {
    return model.family === "planar" ? planar(model, q) : model.family === "tree" ? tree(model, q, R) : spatial(model, q, R);
  }
  root.spacearmPose = spacearmPose;
  if (typeof module !== "undefined" && module.exports) module.exports = {spacearmPose: spacearmPose};
})(typeof window !== "undefined" ? window : globalThis);
