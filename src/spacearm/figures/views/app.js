// The page script of every spacearm view: reads window.SPACEARM (written by page.py) and draws
// with Plotly. Modes: "arm" (one robot, a slider per joint and the bus attitude), "replay"
// (a recorded motion, frame by frame) and "front" (a Pareto front, traces built in Python).
"use strict";
(function () {
  var D = window.SPACEARM, plot = document.getElementById("plot");
  var controls = document.getElementById("controls"), readout = document.getElementById("readout");
  var CONFIG = {displaylogo: false, responsive: true, showLink: false};
  var DEG = Math.PI / 180;

  var M = D.model || {joint_kinds: [], joint_names: [], posture: {base_turn: null}, plane: null};
  // A robot that moves in a plane is drawn flat, seen along the plane's normal; a posture
  // that holds the bus attitude (base_turn) gets a slider for it instead of roll, pitch, yaw.
  var plane = M.plane, turn = M.posture.base_turn;
  // Box corner c has signs (x, y, z) = bits (4, 2, 1); faces as two triangles each.
  var FACES = [[0,1,3],[0,3,2],[4,5,7],[4,7,6],[0,1,5],[0,5,4],[2,3,7],[2,7,6],[0,2,6],[0,6,4],[1,3,7],[1,7,5]];
  var EDGES = [[0,1],[0,2],[0,4],[1,3],[1,5],[2,3],[2,6],[3,7],[4,5],[4,6],[5,7],[6,7]];
  function cols(points) { return [points.map(function (p) { return p[0]; }), points.map(function (p) { return p[1]; }), points.map(function (p) { return p[2]; })]; }
  function edgeLine(corners) {
    var pts = []; EDGES.forEach(function (e) { pts.push(corners[e[0]], corners[e[1]], [null, null, null]); }); return cols(pts);
  }
  function rpy(r, p, y) {
    var cr = Math.cos(r), sr = Math.sin(r), cp = Math.cos(p), sp = Math.sin(p), cy = Math.cos(y), sy = Math.sin(y);
    return [[cy*cp, cy*sp*sr - sy*cr, cy*sp*cr + sy*sr], [sy*cp, sy*sp*sr + cy*cr, sy*sp*cr - cy*sr], [-sp, cp*sr, cp*cr]];
  }
  // One colour per arm (matplotlib's and Plotly's default cycle); joints several arms share in grey.
  var ARM_COLORS = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#17becf"];
  var SHARED = "#595959";
  function segmentLine(segments) {
    var pts = []; segments.forEach(function (s) { pts.push(s[0], s[1], [null, null, null]); }); return cols(pts);
  }
  // The joints on tip t's path from its mount, in order (the whole chain of a serial arm).
  function tipPath(model, t) {
    var path = [];
    for (var b = model.tip_bodies[t]; b >= 0; b = model.parents[b]) path.unshift(b);
    return path;
  }
  function busTraces(pose) {
    var bus = cols(pose.corners), edges = edgeLine(pose.corners);
    return [
      {type: "mesh3d", x: bus[0], y: bus[1], z: bus[2], i: FACES.map(function (f) { return f[0]; }),
       j: FACES.map(function (f) { return f[1]; }), k: FACES.map(function (f) { return f[2]; }),
       color: "#9aa7b8", opacity: 0.35, flatshading: true, name: "bus (equivalent box)", showlegend: true, hoverinfo: "name"},
      {type: "scatter3d", mode: "lines", x: edges[0], y: edges[1], z: edges[2], line: {color: "#56657a", width: 3},
       name: "bus edges", showlegend: false, hoverinfo: "skip"}
    ];
  }
  // Several tips: bus, bus centroid to each mount, mount frames (x, y, z), the shared joints,
  // each arm's links, the tips. Their number depends on the model only, never on the pose.
  function armsTraces(pose, model) {
    var k = model.tip_bodies.length, L = 0.15;
    var toMounts = segmentLine(pose.mounts.map(function (m) { return [pose.bus, m]; }));
    var traces = busTraces(pose).concat([
      {type: "scatter3d", mode: "lines", x: toMounts[0], y: toMounts[1], z: toMounts[2], line: {color: "#56657a", width: 5},
       name: "bus centroid to the mounts", hoverinfo: "name"}
    ]);
    ["#d62728", "#2ca02c", "#1f77b4"].forEach(function (color, c) {
      var axis = segmentLine(pose.mounts.map(function (m, r) {
        var a = pose.mountAxes[r]; return [m, add3(m, [L * a[0][c], L * a[1][c], L * a[2][c]])];
      }));
      traces.push({type: "scatter3d", mode: "lines", x: axis[0], y: axis[1], z: axis[2], line: {color: color, width: 5},
                   name: "mount " + "xyz"[c] + " axes", showlegend: c === 0, hoverinfo: "name"});
    });
    var groups = model.owner.indexOf(-1) >= 0 ? [-1] : [];
    for (var t = 0; t < k; t++) groups.push(t);
    groups.forEach(function (t) {
      var mine = pose.segments.filter(function (s, i) { return pose.owner[i] === t; }), xyz = segmentLine(mine);
      var color = t < 0 ? SHARED : ARM_COLORS[t % ARM_COLORS.length];
      traces.push({type: "scatter3d", mode: "lines+markers", x: xyz[0], y: xyz[1], z: xyz[2],
                   line: {color: color, width: 12}, marker: {size: 4, color: color},
                   name: t < 0 ? "shared joints" : model.tip_names[t], hoverinfo: "name+x+y+z"});
    });
    var tips = cols(pose.tips);
    traces.push({type: "scatter3d", mode: "markers", x: tips[0], y: tips[1], z: tips[2],
                 marker: {size: 7, symbol: "diamond", color: pose.tips.map(function (p, t) { return ARM_COLORS[t % ARM_COLORS.length]; }),
                          line: {color: "black", width: 1}},
                 name: "tips", text: model.tip_names, hoverinfo: "text+x+y+z"});
    return traces;
  }
  function add3(a, b) { return [a[0] + b[0], a[1] + b[1], a[2] + b[2]]; }
  // One tip: bus, bus centroid to the mount and joint 1, the links through the joint origins to the tip.
  function armTraces(pose, model) {
    var path = tipPath(model, 0), tip = pose.tips[0];
    var points = path.map(function (j) { return pose.joints[j]; }).concat([tip]), arm = cols(points);
    var mount = pose.mounts[-1 - model.parents[path[0]]], root = cols([pose.bus, mount, points[0]]);
    return busTraces(pose).concat([
      {type: "scatter3d", mode: "lines+markers", x: root[0], y: root[1], z: root[2], line: {color: "#56657a", width: 6},
       marker: {size: 3, color: "#56657a"}, name: "bus centroid to joint 1", hoverinfo: "name"},
      {type: "scatter3d", mode: "lines+markers", x: arm[0], y: arm[1], z: arm[2], line: {color: "#1f77b4", width: 14},
       marker: {size: 6, color: "#0b3c68"}, name: "links (joint origins, tip)",
       text: path.map(function (j) { return model.joint_names[j]; }).concat(["tip"]), hoverinfo: "text+x+y+z"},
      {type: "scatter3d", mode: "markers", x: [tip[0]], y: [tip[1]], z: [tip[2]], marker: {size: 7, color: "#d62728", symbol: "diamond"},
       name: "tip", hoverinfo: "name+x+y+z"}
    ]);
  }
  // The traces that move with the pose, in this order.
  function poseTraces(pose, model) {
    model = model || M;
    return model.tip_bodies.length > 1 ? armsTraces(pose, model) : armTraces(pose, model);
  }
  function fixedTraces() {
    return [{type: "scatter3d", mode: "markers", x: [0], y: [0], z: [0], marker: {size: 5, color: "black", symbol: "x"},
             name: "system centroid (origin)", hoverinfo: "name"}];
  }
  function sceneLayout(E, plane) {
    return {aspectmode: "cube", xaxis: {range: [-E, E], title: {text: "x, m"}}, yaxis: {range: [-E, E], title: {text: "y, m"}},
            zaxis: {range: [-E, E], title: {text: "z, m"}},
            camera: plane ? {eye: {x: 2.0 * plane.normal[0], y: 2.0 * plane.normal[1], z: 2.0 * plane.normal[2]},
                            up: {x: 0, y: 1, z: 0}, projection: {type: "orthographic"}}
                         : {eye: {x: 1.4, y: -1.4, z: 1.0}}};
  }
  if (D.mode === "front") {
    Plotly.newPlot(plot, D.traces, D.layout, CONFIG);
    readout.textContent = D.readout || "";
    var robotDiv = document.createElement("div"); robotDiv.style.height = "320px"; controls.appendChild(robotDiv);
    plot.on("plotly_click", function (ev) {
      var p = ev.points[0];
      if (!p) return;
      readout.textContent = String(p.text || "").replace(/<br>/g, "\n");
      var r = D.robots && p.customdata !== undefined && p.customdata !== null ? D.robots[p.customdata] : null;
      if (!r) return;
      Plotly.react(robotDiv, poseTraces(spacearmPose(r.model, r.posture, null), r.model).concat(fixedTraces()),
        {margin: {l: 0, r: 0, t: 20, b: 0}, showlegend: false, title: {text: "the picked design", font: {size: 12}},
         scene: sceneLayout(r.extent, r.model.plane)}, CONFIG);
    });
    document.body.dataset.spacearm = "ready";
    return;
  }
  // A sphere of radius r about the origin as a mesh (rings x segments).
  function sphere(r, color, name) {
    var x = [], y = [], z = [], I = [], J = [], K = [], rings = 14, segs = 28;
    for (var a = 0; a <= rings; a++) for (var b = 0; b < segs; b++) {
      var t = Math.PI * a / rings, p = 2 * Math.PI * b / segs;
      x.push(r * Math.sin(t) * Math.cos(p)); y.push(r * Math.sin(t) * Math.sin(p)); z.push(r * Math.cos(t));
    }
    for (a = 0; a < rings; a++) for (b = 0; b < segs; b++) {
      var i0 = a * segs + b, i1 = a * segs + (b + 1) % segs, i2 = i0 + segs, i3 = i1 + segs;
      I.push(i0, i1); J.push(i2, i2); K.push(i1, i3);
    }
    return {type: "mesh3d", x: x, y: y, z: z, i: I, j: J, k: K, color: color, opacity: 0.15, name: name,
            showlegend: true, hoverinfo: "name"};
  }
  if (D.mode === "shells") {
    var showDesign = function (k) {
      var d = D.designs[k], traces = poseTraces(spacearmPose(d.model, d.posture, null), d.model).concat(fixedTraces());
      d.shells.forEach(function (s) { if (s.radius !== null) traces.push(sphere(s.radius, s.color, s.name)); });
      Plotly.react(plot, traces, {margin: {l: 0, r: 0, t: 30, b: 0}, legend: {x: 0, y: 1},
        title: {text: D.title, font: {size: 14}}, scene: sceneLayout(D.extent, false), uirevision: "keep"}, CONFIG);
      readout.textContent = "design " + (k + 1) + " of " + D.designs.length + "\n" + d.label + "\n" +
        d.shells.map(function (s) { return s.name; }).join("\n");
    };
    slider("design", 0, D.designs.length - 1, 1, 0, "", function (v) { showDesign(v); });
    showDesign(0);
    document.body.dataset.spacearm = "ready";
    return;
  }
  var E = D.extent;
  var layout = {
    margin: {l: 0, r: 0, t: 30, b: 0}, legend: {x: 0, y: 1},
    title: {text: D.title || "", font: {size: 14}},
    scene: sceneLayout(E, plane)
  };
  var MOVING = [0, 1, 2, 3, 4];
  function restyle(traces, indices) {
    var update = {x: [], y: [], z: []};
    traces.forEach(function (t) { update.x.push(t.x); update.y.push(t.y); update.z.push(t.z); });
    Plotly.restyle(plot, update, indices);
  }
  function fmt(v) { return (v >= 0 ? " " : "") + v.toFixed(4); }
  function tipText(pose) {
    if (pose.tips.length > 1) {
      return "tips about the system centroid, m" + pose.tips.map(function (t, i) {
        return "\n" + M.tip_names[i] + "\n x " + fmt(t[0]) + "\n y " + fmt(t[1]) + "\n z " + fmt(t[2]);
      }).join("");
    }
    var t = pose.tips[0];
    return "tip about the system centroid, m\n x " + fmt(t[0]) + "\n y " + fmt(t[1]) + (plane ? "" : "\n z " + fmt(t[2]));
  }
  function slider(label, min, max, step, value, unit, onInput) {
    var div = document.createElement("div"); div.className = "control";
    var lab = document.createElement("label"), name = document.createElement("span"), val = document.createElement("span");
    name.textContent = label; lab.appendChild(name); lab.appendChild(val);
    var input = document.createElement("input"); input.type = "range";
    input.min = min; input.max = max; input.step = step; input.value = value;
    var show = function () { val.textContent = Number(input.value).toFixed(unit === "m" ? 3 : unit === "" ? 0 : 1) + " " + unit; };
    input.addEventListener("input", function () { show(); onInput(Number(input.value)); });
    show(); div.appendChild(lab); div.appendChild(input); controls.appendChild(div);
    return input;
  }

  if (D.mode === "arm") {
    var posture = D.posture.slice(), attitude = (D.rpy || [0, 0, 0]).slice();
    var pose = function () { return spacearmPose(M, posture, turn ? null : rpy(attitude[0], attitude[1], attitude[2])); };
    var update = function () { var p = pose(); restyle(poseTraces(p), MOVING); readout.textContent = tipText(p); };
    var first = pose();
    var moving = poseTraces(first);
    MOVING = moving.map(function (t, i) { return i; });
    Plotly.newPlot(plot, moving.concat(fixedTraces()), layout, CONFIG);
    readout.textContent = tipText(first);
    var offset = M.posture.joint_offset;
    if (turn) {
      slider(turn.name, -180, 180, 0.5, posture[turn.index] / DEG, "deg", function (v) { posture[turn.index] = v * DEG; update(); });
    }
    M.joint_names.forEach(function (name, i) {
      var prismatic = M.joint_kinds[i] === "prismatic", lo = M.lower[i], hi = M.upper[i];
      if (prismatic) {
        lo = lo === null ? -0.5 : lo; hi = hi === null ? 0.5 : hi;
        slider(name + " (m)", lo, hi, (hi - lo) / 400, posture[i + offset], "m", function (v) { posture[i + offset] = v; update(); });
      } else {
        lo = lo === null ? -180 : Math.max(lo / DEG, -360); hi = hi === null ? 180 : Math.min(hi / DEG, 360);
        slider(name, lo, hi, 0.5, posture[i + offset] / DEG, "deg", function (v) { posture[i + offset] = v * DEG; update(); });
      }
    });
    if (!turn) {
      ["bus roll", "bus pitch", "bus yaw"].forEach(function (name, i) {
        slider(name, -180, 180, 0.5, attitude[i] / DEG, "deg", function (v) { attitude[i] = v * DEG; update(); });
      });
    }
    window.spacearmView = {pose: pose, posture: posture, attitude: attitude, update: update};
    document.body.dataset.spacearm = "ready";
    return;
  }

  if (D.mode === "replay") {
    var F = D.frames, count = F.q.length, frame = 0, timer = null;
    var poseAt = function (k) { return spacearmPose(M, F.q[k], F.R ? F.R[k] : null); };
    var tip3 = F.tip.map(function (t) { return [t[0], t[1], t.length > 2 ? t[2] : 0]; });
    var turnedBy = function (k) {
      if (turn) return (F.q[k][turn.index] - F.q[0][turn.index]) / DEG;
      var a = F.R[0], b = F.R[k], tr = 0;
      for (var i = 0; i < 3; i++) for (var j = 0; j < 3; j++) tr += a[j][i] * b[j][i];
      return Math.acos(Math.max(-1, Math.min(1, (tr - 1) / 2))) / DEG;
    };
    var trace = function (k) { return {x: tip3.slice(0, k + 1).map(function (p) { return p[0]; }),
      y: tip3.slice(0, k + 1).map(function (p) { return p[1]; }), z: tip3.slice(0, k + 1).map(function (p) { return p[2]; })}; };
    var path = cols(tip3), extra = [
      {type: "scatter3d", mode: "lines", x: path[0], y: path[1], z: path[2], line: {color: "#f2a0a0", width: 2},
       name: "tip path (whole maneuver)", hoverinfo: "skip"},
      {type: "scatter3d", mode: "lines", x: [tip3[0][0]], y: [tip3[0][1]], z: [tip3[0][2]], line: {color: "#d62728", width: 5},
       name: "tip trace so far", hoverinfo: "skip"}
    ];
    if (D.target) {
      var g = D.target;
      extra.push({type: "scatter3d", mode: "markers", x: [g[0]], y: [g[1]], z: [g.length > 2 ? g[2] : 0],
        marker: {size: 6, color: "#2ca02c", symbol: "circle-open"}, name: "target", hoverinfo: "name+x+y+z"});
    }
    var firstTraces = poseTraces(poseAt(0));
    MOVING = firstTraces.map(function (t, i) { return i; });  // several arms draw more traces than one
    var TRACE = MOVING.length + 2;
    var show = function (k) {
      frame = k; var p = poseAt(k), t = trace(k);
      var traces = poseTraces(p); traces.push(t);
      restyle(traces, MOVING.concat([TRACE]));
      readout.textContent = "frame " + (k + 1) + " of " + count + (F.phase ? " (" + F.phase[k] + ")" : "") +
        "\nbus turned " + turnedBy(k).toFixed(3) + " deg from the start\n" + tipText(p);
    };
    Plotly.newPlot(plot, firstTraces.concat(fixedTraces(), extra), layout, CONFIG);
    var play = document.createElement("button"); play.textContent = "play"; controls.appendChild(play);
    var scrub = slider("frame", 0, count - 1, 1, 0, "", function (v) { stop(); show(v); });
    var stop = function () { if (timer) { clearInterval(timer); timer = null; play.textContent = "play"; } };
    var interval = Math.max(16, 1000 * (D.seconds || 6) / count), stride = Math.max(1, Math.round(16 * count / (1000 * (D.seconds || 6))));
    play.addEventListener("click", function () {
      if (timer) { stop(); return; }
      if (frame >= count - 1) frame = 0;
      play.textContent = "pause";
      timer = setInterval(function () {
        var k = Math.min(count - 1, frame + stride); scrub.value = k; scrub.dispatchEvent(new Event("change"));
        show(k); if (k >= count - 1) stop();
      }, interval);
    });
    show(0);
    window.spacearmView = {poseAt: poseAt, show: show, count: count};
    document.body.dataset.spacearm = "ready";
  }
})();
