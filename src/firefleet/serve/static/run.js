// The run page: a recorded run replayed to scale, with a slider, play/pause and speed,
// layers found in the run's arrays, its signals over time and its claims.
"use strict";

(async function () {
  const runId = decodeURIComponent(location.pathname.split("/").pop());
  const response = await fetch("/api/run/" + encodeURIComponent(runId));
  const data = await response.json();
  const summary = data.summary, doc = data.layers;
  document.title = "firefleet: " + summary.name;
  document.getElementById("title").textContent = summary.name + " (" + summary.scenario + ")";
  FF.claimsTable(data.metrics);
  FF.figures(runId, data.figures);
  const state = { k: 0, playing: false, speed: 1, last: null, on: {} };
  window.firefleet = { data: data, state: state, view: null, drawn: 0 };
  if (!doc) {
    document.querySelector("#scene").closest(".panel").hidden = true;
    document.body.dataset.ready = "1";
    return;
  }
  const canvas = document.getElementById("scene"), ctx = canvas.getContext("2d");
  const slider = document.getElementById("slider");
  slider.max = String(doc.t.length - 1);
  const n = doc.pose.length ? doc.pose[0].length : 0;

  // the layers this run has, each with a checkbox
  const layers = [["robots", "robots"], ["trajectories", "trajectories"], ["labels", "numbers"]];
  if (doc.scene.paths && doc.scene.paths.length) layers.push(["paths", "paths"]);
  if (doc.scene.obstacles && doc.scene.obstacles.length) layers.push(["obstacles", "obstacles"]);
  if (Object.keys(doc.points).length) layers.push(["points", Object.keys(doc.points).join(", ")]);
  for (const name in doc.estimates) layers.push(["estimate:" + name, name + " (dashed)"]);
  if (Object.keys(doc.particles).length) layers.push(["particles", "particles"]);
  if (Object.keys(doc.landmarks).length) layers.push(["landmarks", "landmarks"]);
  if (doc.ranges.length) layers.push(["ranges", doc.ranges.map(function (r) { return r.name; }).join(", ")]);
  if (doc.map) layers.push(["map", "map"]);
  const box = document.getElementById("layers");
  for (const layer of layers) {
    state.on[layer[0]] = !(layer[0] === "labels" && n > 20);  // 200 numbers hide the team
    const label = document.createElement("label"), input = document.createElement("input");
    input.type = "checkbox"; input.checked = state.on[layer[0]]; input.dataset.layer = layer[0];
    input.addEventListener("change", function () { state.on[layer[0]] = input.checked; draw(); });
    label.appendChild(input); label.appendChild(document.createTextNode(" " + layer[1]));
    box.appendChild(label);
  }
  const legend = document.getElementById("legend");
  for (let i = 0; i < Math.min(n, 20); i++) {
    const span = document.createElement("span");
    span.innerHTML = '<i class="swatch" style="background:' + FF.color(i) + '"></i>robot ' + (i + 1);
    legend.appendChild(span);
  }

  // signals: the main ones shown, the others a click away
  const seriesBox = document.getElementById("series"), plots = document.getElementById("plots");
  const names = Object.keys(doc.series);
  const shown = {};
  for (const name of names) shown[name] = FF.MAIN_SIGNALS.indexOf(name) >= 0;
  const layoutPlots = function () {
    plots.innerHTML = "";
    for (const name of names) if (shown[name]) {
      const c = document.createElement("canvas"); c.className = "plot"; c.dataset.series = name;
      plots.appendChild(c);
    }
    draw();
  };
  for (const name of names) {
    const label = document.createElement("label"), input = document.createElement("input");
    input.type = "checkbox"; input.checked = shown[name];
    input.addEventListener("change", function () { shown[name] = input.checked; layoutPlots(); });
    label.appendChild(input); label.appendChild(document.createTextNode(" " + name));
    seriesBox.appendChild(label);
  }

  const bounds = FF.bounds(doc);
  const thermalCanvas = document.getElementById("thermal");
  if (doc.thermal) document.getElementById("thermal-panel").hidden = false;

  function draw() {
    FF.fitCanvas(canvas);
    const view = FF.view(canvas, bounds);
    window.firefleet.view = { scale: view.scale, xmin: view.xmin, ymax: view.ymax, ox: view.ox, oy: view.oy };
    FF.drawScene(ctx, view, doc, state.k, state.on);
    const t = doc.t[state.k];
    document.getElementById("time").textContent = "t = " + t.toFixed(2) + " s";
    for (const c of plots.querySelectorAll("canvas")) FF.plot(c, doc.t, doc.series[c.dataset.series], c.dataset.series, t);
    if (doc.thermal) {
      let j = 0;
      while (j + 1 < doc.thermal.t.length && doc.thermal.t[j + 1] <= t) j++;
      let frame = doc.thermal.frames[j];
      if (Array.isArray(frame[0][0])) frame = frame[0];  // one frame per robot: robot 1's
      const range = FF.thermal(thermalCanvas, frame);
      document.getElementById("thermal-range").textContent = range[0].toFixed(1) + " .. " + range[1].toFixed(1);
    }
    window.firefleet.drawn += 1;
  }

  slider.addEventListener("input", function () { state.k = Number(slider.value); draw(); });
  document.getElementById("speed").addEventListener("change", function (e) { state.speed = Number(e.target.value); });
  const play = document.getElementById("play");
  play.addEventListener("click", function () {
    state.playing = !state.playing;
    play.textContent = state.playing ? "pause" : "play";
    if (state.playing && state.k >= doc.t.length - 1) state.k = 0;
    state.last = null;
    if (state.playing) requestAnimationFrame(tick);
  });
  function tick(now) {
    if (!state.playing) return;
    if (state.last !== null) {
      const target = doc.t[state.k] + (now - state.last) / 1000 * state.speed;
      while (state.k + 1 < doc.t.length && doc.t[state.k + 1] <= target) state.k++;
      if (state.k >= doc.t.length - 1) { state.playing = false; play.textContent = "play"; }
      slider.value = String(state.k);
      draw();
    }
    state.last = now;
    if (state.playing) requestAnimationFrame(tick);
  }
  window.addEventListener("resize", draw);
  layoutPlots();
  document.body.dataset.ready = "1";
})();

FF.claimsTable = function (metrics) {
  const body = document.querySelector("#claims tbody");
  for (const claim of metrics.claims || []) {
    const row = document.createElement("tr");
    const measured = claim.measured;
    const shown = Array.isArray(measured)
      ? measured.map(function (v) { return v === null ? "-" : Number(v).toPrecision(6); }).join(", ")
      : (measured === null ? "-" : Number(measured).toPrecision(6));
    const cells = [claim.name, claim.expected, shown, claim.passed ? "yes" : "NO", claim.source || ""];
    cells.forEach(function (text, i) {
      const cell = document.createElement("td");
      cell.textContent = String(text);
      if (i === 2) { cell.className = "num"; cell.dataset.measured = JSON.stringify(measured); }
      if (i === 3) cell.className = claim.passed ? "ok" : "bad";
      row.appendChild(cell);
    });
    body.appendChild(row);
  }
  const p = metrics.provenance || {};
  if (p.command) document.getElementById("provenance").textContent =
    "Made by: " + p.command + (p.git_commit ? " (commit " + p.git_commit + ")" : "") + "; seed " + p.seed + ".";
};

FF.figures = function (runId, names) {
  const box = document.getElementById("figures");
  if (!names.length) { document.getElementById("figures-panel").hidden = true; return; }
  for (const name of names) {
    const img = document.createElement("img");
    img.src = "/api/run/" + encodeURIComponent(runId) + "/file/" + encodeURIComponent(name);
    img.alt = name; img.loading = "lazy";
    box.appendChild(img);
  }
};
