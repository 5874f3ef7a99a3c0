// The live page: frames of a running simulation over a websocket, drawn as they come.
// The server sends the newest frame when this page is ready for one: a slow page
// skips frames, it never holds the simulation back.
"use strict";

(function () {
  const canvas = document.getElementById("scene"), ctx = canvas.getContext("2d");
  const live = { frames: 0, last: null, scene: null, doc: null, finished: false };
  window.firefleetLive = live;
  const token = new URLSearchParams(location.search).get("token");
  const scheme = location.protocol === "https:" ? "wss://" : "ws://";
  const socket = new WebSocket(scheme + location.host + "/ws/live" + (token ? "?token=" + encodeURIComponent(token) : ""));
  const status = document.getElementById("status");
  let pending = false;

  function emptyDoc(scene) {
    return { t: [], pose: [], scene: scene || {}, estimates: {}, points: {}, landmarks: {},
      particles: {}, ranges: [], map: null };
  }
  live.doc = emptyDoc(null);

  function draw() {
    pending = false;
    const doc = live.doc;
    FF.fitCanvas(canvas);
    if (!doc.pose.length) return;
    const view = FF.view(canvas, FF.bounds(doc));
    live.view = { scale: view.scale, xmin: view.xmin, ymax: view.ymax, ox: view.ox, oy: view.oy };
    FF.drawScene(ctx, view, doc, doc.pose.length - 1,
      { robots: true, trajectories: true, labels: true, paths: true, obstacles: true, points: true });
  }

  socket.addEventListener("open", function () { status.textContent = "connected"; });
  socket.addEventListener("close", function () { status.textContent = live.finished ? "run finished" : "disconnected"; });
  socket.addEventListener("message", function (event) {
    const msg = JSON.parse(event.data);
    if (msg.type === "hello") {
      live.scene = msg.scene;
      live.doc = emptyDoc(msg.scene);
      document.getElementById("title").textContent = "live: " + msg.scenario;
      const legend = document.getElementById("legend");
      legend.innerHTML = "";
      for (let i = 0; i < Math.min((msg.scene || {}).n_robots || 0, 20); i++) {
        const span = document.createElement("span");
        span.innerHTML = '<i class="swatch" style="background:' + FF.color(i) + '"></i>robot ' + (i + 1);
        legend.appendChild(span);
      }
      return;
    }
    if (msg.total) document.getElementById("progress").value = msg.done / msg.total;
    if (msg.type !== "frame") { status.textContent = "simulating (no poses until the end)"; return; }
    live.frames += 1;
    live.last = msg;
    live.doc.t.push(msg.t);
    live.doc.pose.push(msg.pose);
    document.getElementById("time").textContent = "t = " + msg.t.toFixed(2) + " s";
    document.getElementById("frames").textContent = live.frames + " frames";
    if (msg.finished) { live.finished = true; status.textContent = "run finished"; }
    else status.textContent = "simulating";
    if (!pending) { pending = true; requestAnimationFrame(draw); }
  });
  window.addEventListener("resize", draw);
})();
