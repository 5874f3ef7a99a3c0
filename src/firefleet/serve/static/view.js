// Drawing a team to scale on a canvas: the world -> pixel transform and every layer.
// Shared by the run page (replay) and the live page. Plain JS, no library.
"use strict";

const FF = {};

FF.PALETTE = ["#d62728", "#1f77b4", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b",
  "#e377c2", "#17becf", "#bcbd22", "#7f7f7f"];

FF.color = function (i) {
  if (i < FF.PALETTE.length) return FF.PALETTE[i];
  return "hsl(" + ((i * 137.508) % 360).toFixed(1) + ", 65%, 45%)";
};

// Bounds of everything drawn: [xmin, xmax, ymin, ymax] in metres.
FF.bounds = function (doc) {
  let b = [Infinity, -Infinity, Infinity, -Infinity];
  const add = function (x, y) {
    if (x === null || y === null || !isFinite(x) || !isFinite(y)) return;
    if (x < b[0]) b[0] = x; if (x > b[1]) b[1] = x;
    if (y < b[2]) b[2] = y; if (y > b[3]) b[3] = y;
  };
  for (const sample of doc.pose || []) for (const p of sample) add(p[0], p[1]);
  const scene = doc.scene || {};
  for (const path of scene.paths || []) for (const p of path) add(p[0], p[1]);
  for (const o of scene.obstacles || []) { add(o[0] - o[2], o[1] - o[2]); add(o[0] + o[2], o[1] + o[2]); }
  for (const name in doc.points || {}) for (const sample of doc.points[name]) for (const p of sample) add(p[0], p[1]);
  for (const name in doc.landmarks || {}) for (const p of doc.landmarks[name]) add(p[0], p[1]);
  if (doc.map) {
    const m = doc.map, h = m.cells.length, w = h ? m.cells[0].length : 0;
    add(m.origin_m[0], m.origin_m[1]);
    add(m.origin_m[0] + w * m.resolution_m, m.origin_m[1] + h * m.resolution_m);
  }
  if (scene.formation_radius_m && doc.points && doc.points.leader_xy_m) {
    const r = scene.formation_radius_m;
    for (const sample of doc.points.leader_xy_m) for (const p of sample) { add(p[0] - r, p[1] - r); add(p[0] + r, p[1] + r); }
  }
  if (!isFinite(b[0])) b = [-1, 1, -1, 1];
  const pad = Math.max(0.5, 0.05 * Math.max(b[1] - b[0], b[3] - b[2]));
  return [b[0] - pad, b[1] + pad, b[2] - pad, b[3] + pad];
};

// The transform: one scale for x and y (to scale), y up, the bounds centred.
FF.view = function (canvas, b) {
  const w = canvas.width, h = canvas.height;
  const scale = Math.min(w / (b[1] - b[0]), h / (b[3] - b[2]));
  const ox = (w - scale * (b[1] - b[0])) / 2, oy = (h - scale * (b[3] - b[2])) / 2;
  return {
    scale: scale, xmin: b[0], ymax: b[3], ox: ox, oy: oy, width: w, height: h,
    px: function (x, y) { return [ox + (x - b[0]) * scale, oy + (b[3] - y) * scale]; },
  };
};

FF.fitCanvas = function (canvas) {
  const ratio = window.devicePixelRatio || 1;
  canvas.width = Math.round(canvas.clientWidth * ratio);
  canvas.height = Math.round(canvas.clientHeight * ratio);
};

FF.line = function (ctx, view, points, style, width, dash) {
  ctx.save();
  ctx.strokeStyle = style; ctx.lineWidth = width; ctx.setLineDash(dash || []);
  ctx.beginPath();
  let pen = false;
  for (const p of points) {
    if (!p || p[0] === null || p[1] === null) { pen = false; continue; }
    const q = view.px(p[0], p[1]);
    if (pen) ctx.lineTo(q[0], q[1]); else ctx.moveTo(q[0], q[1]);
    pen = true;
  }
  ctx.stroke();
  ctx.restore();
};

FF.circle = function (ctx, view, x, y, r, stroke, fill, dash) {
  const q = view.px(x, y);
  ctx.save();
  ctx.beginPath();
  ctx.setLineDash(dash || []);
  ctx.arc(q[0], q[1], Math.max(r * view.scale, 1), 0, 2 * Math.PI);
  if (fill) { ctx.fillStyle = fill; ctx.fill(); }
  if (stroke) { ctx.strokeStyle = stroke; ctx.lineWidth = 1.5; ctx.stroke(); }
  ctx.restore();
};

// A grid and a scale bar, so that distances can be read off.
FF.grid = function (ctx, view) {
  const span = (view.width / view.scale);
  const steps = [0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500];
  const step = steps.find(function (s) { return span / s <= 12; }) || 1000;
  ctx.save();
  ctx.strokeStyle = "#eef0f2"; ctx.lineWidth = 1;
  const x0 = Math.floor(view.xmin / step) * step;
  const ymin = view.ymax - view.height / view.scale;
  for (let x = x0; x <= view.xmin + span; x += step) {
    const q = view.px(x, 0); ctx.beginPath(); ctx.moveTo(q[0], 0); ctx.lineTo(q[0], view.height); ctx.stroke();
  }
  for (let y = Math.floor(ymin / step) * step; y <= view.ymax; y += step) {
    const q = view.px(0, y); ctx.beginPath(); ctx.moveTo(0, q[1]); ctx.lineTo(view.width, q[1]); ctx.stroke();
  }
  const len = step * view.scale, x1 = 12, y1 = view.height - 14;
  ctx.strokeStyle = "#333"; ctx.lineWidth = 2;
  ctx.beginPath(); ctx.moveTo(x1, y1); ctx.lineTo(x1 + len, y1); ctx.stroke();
  ctx.fillStyle = "#333"; ctx.font = "12px system-ui, sans-serif";
  ctx.fillText(step + " m", x1, y1 - 5);
  ctx.restore();
};

FF.drawMap = function (ctx, view, map) {
  const h = map.cells.length, w = h ? map.cells[0].length : 0;
  if (!w) return;
  const image = new ImageData(w, h);
  for (let r = 0; r < h; r++) for (let c = 0; c < w; c++) {
    const v = map.cells[r][c], i = 4 * (r * w + c);
    const g = v === null ? 205 : Math.round(255 * (1 - Math.min(Math.max(v, 0), 1)));
    image.data[i] = g; image.data[i + 1] = g; image.data[i + 2] = g; image.data[i + 3] = 255;
  }
  const off = document.createElement("canvas");
  off.width = w; off.height = h;
  off.getContext("2d").putImageData(image, 0, 0);
  const top = view.px(map.origin_m[0], map.origin_m[1] + h * map.resolution_m);  // row 0 is the top
  ctx.save();
  ctx.imageSmoothingEnabled = false;
  ctx.drawImage(off, top[0], top[1], w * map.resolution_m * view.scale, h * map.resolution_m * view.scale);
  ctx.restore();
};

// A robot: a filled disc in its colour (its centre is the pose), a black heading stroke.
FF.robot = function (ctx, view, pose, radius_m, color, label) {
  const q = view.px(pose[0], pose[1]);
  const r = Math.max(radius_m * view.scale, 6);
  ctx.save();
  ctx.beginPath(); ctx.arc(q[0], q[1], r, 0, 2 * Math.PI);
  ctx.fillStyle = color; ctx.fill();
  ctx.strokeStyle = "#000"; ctx.lineWidth = 2;
  ctx.beginPath(); ctx.moveTo(q[0], q[1]);
  ctx.lineTo(q[0] + 1.6 * r * Math.cos(pose[2]), q[1] - 1.6 * r * Math.sin(pose[2])); ctx.stroke();
  if (label) { ctx.fillStyle = "#222"; ctx.font = "12px system-ui, sans-serif"; ctx.fillText(label, q[0] + r + 3, q[1] - r - 2); }
  ctx.restore();
};

// Everything at sample k; `on` says which layers are shown.
FF.drawScene = function (ctx, view, doc, k, on) {
  ctx.save();
  ctx.fillStyle = "#fff"; ctx.fillRect(0, 0, view.width, view.height);
  ctx.restore();
  if (doc.map && on.map) FF.drawMap(ctx, view, doc.map);
  FF.grid(ctx, view);
  const scene = doc.scene || {};
  const n = doc.pose.length ? doc.pose[0].length : 0;
  if (on.paths) (scene.paths || []).forEach(function (path, i) { FF.line(ctx, view, path, FF.color(i), 1.5, [6, 4]); });
  if (on.obstacles) for (const o of scene.obstacles || []) FF.circle(ctx, view, o[0], o[1], o[2], "#555", "rgba(90,90,90,0.35)");
  ctx.save();
  ctx.globalAlpha = 0.5;
  if (on.trajectories) for (let i = 0; i < n; i++) {
    const track = [];
    for (let j = 0; j <= k; j++) track.push(doc.pose[j][i]);
    FF.line(ctx, view, track, FF.color(i), 1.5);
  }
  ctx.restore();
  for (const name in doc.estimates || {}) {
    if (!on["estimate:" + name]) continue;
    for (let i = 0; i < n; i++) {
      const track = [];
      for (let j = 0; j <= k; j++) track.push(doc.estimates[name][j][i]);
      FF.line(ctx, view, track, FF.color(i), 1, [3, 3]);
    }
  }
  if (on.particles) for (const name in doc.particles || {}) {
    const cloud = doc.particles[name];
    let j = 0;
    while (j + 1 < cloud.t.length && cloud.t[j + 1] <= doc.t[k]) j++;
    ctx.fillStyle = "rgba(120,60,160,0.5)";
    const flat = [].concat.apply([], cloud.xy[j].map(function (p) { return Array.isArray(p[0]) ? p : [p]; }));
    for (const p of flat) { const q = view.px(p[0], p[1]); ctx.fillRect(q[0] - 1, q[1] - 1, 2, 2); }
  }
  if (on.landmarks) for (const name in doc.landmarks || {}) for (const p of doc.landmarks[name]) {
    const q = view.px(p[0], p[1]);
    ctx.save(); ctx.strokeStyle = "#000"; ctx.lineWidth = 1.5;
    ctx.beginPath(); ctx.moveTo(q[0] - 4, q[1] - 4); ctx.lineTo(q[0] + 4, q[1] + 4);
    ctx.moveTo(q[0] + 4, q[1] - 4); ctx.lineTo(q[0] - 4, q[1] + 4); ctx.stroke(); ctx.restore();
  }
  if (on.ranges) for (const layer of doc.ranges || []) {
    ctx.save(); ctx.strokeStyle = "rgba(255,140,0,0.55)"; ctx.lineWidth = 1;
    for (let i = 0; i < n; i++) {
      const p = doc.pose[k][i], r = layer.range_m[k][i];
      layer.angle_rad.forEach(function (a, b) {
        if (r[b] === null) return;
        const q0 = view.px(p[0], p[1]), q1 = view.px(p[0] + r[b] * Math.cos(p[2] + a), p[1] + r[b] * Math.sin(p[2] + a));
        ctx.beginPath(); ctx.moveTo(q0[0], q0[1]); ctx.lineTo(q1[0], q1[1]); ctx.stroke();
      });
    }
    ctx.restore();
  }
  if (on.points) for (const name in doc.points || {}) {
    const sample = doc.points[name][k];
    const leader = name.indexOf("leader") >= 0;
    sample.forEach(function (p, i) {
      if (p[0] === null) return;
      const q = view.px(p[0], p[1]);
      ctx.save();
      ctx.strokeStyle = leader ? "#000" : FF.color(i); ctx.lineWidth = 1.5;
      ctx.beginPath();
      if (leader) { ctx.rect(q[0] - 5, q[1] - 5, 10, 10); } else { ctx.arc(q[0], q[1], 4, 0, 2 * Math.PI); }
      ctx.stroke(); ctx.restore();
      if (leader && scene.formation_radius_m) FF.circle(ctx, view, p[0], p[1], scene.formation_radius_m, "#888", null, [4, 4]);
    });
  }
  if (on.robots) for (let i = 0; i < n; i++) {
    const p = doc.pose[k][i];
    if (p[0] === null) continue;
    FF.robot(ctx, view, p, scene.robot_radius_m || 0.1, FF.color(i), on.labels ? String(i + 1) : "");
  }
};

// False colour (black - purple - red - yellow - white) of a thermal frame, min..max.
FF.thermal = function (canvas, frame) {
  const h = frame.length, w = h ? frame[0].length : 0;
  let lo = Infinity, hi = -Infinity;
  for (const row of frame) for (const v of row) if (v !== null) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
  canvas.width = w; canvas.height = h;
  const ctx = canvas.getContext("2d"), image = ctx.createImageData(w, h);
  const stops = [[0, 0, 0], [90, 0, 140], [220, 30, 30], [255, 200, 0], [255, 255, 255]];
  for (let r = 0; r < h; r++) for (let c = 0; c < w; c++) {
    const v = frame[r][c], u = v === null || hi <= lo ? 0 : (v - lo) / (hi - lo);
    const s = Math.min(u * 4, 3.999), a = Math.floor(s), f = s - a, i = 4 * (r * w + c);
    for (let ch = 0; ch < 3; ch++) image.data[i + ch] = stops[a][ch] + f * (stops[a + 1][ch] - stops[a][ch]);
    image.data[i + 3] = 255;
  }
  ctx.putImageData(image, 0, 0);
  return [lo, hi];
};
