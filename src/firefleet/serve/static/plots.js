// Time plots of a run's signals, one small canvas each, with a cursor at the slider's time.
"use strict";

FF.MAIN_SIGNALS = ["wheel_speed_rad_s", "v_m_s", "omega_rad_s", "y_err_m"];

FF.plot = function (canvas, t, values, name, tNow) {
  FF.fitCanvas(canvas);
  const ctx = canvas.getContext("2d"), w = canvas.width, h = canvas.height;
  const left = 48, right = 8, top = 16, bottom = 18;
  ctx.fillStyle = "#fff"; ctx.fillRect(0, 0, w, h);
  // values: T x N, or T x N x C (each robot's channels; the first solid, the rest dashed)
  let lo = Infinity, hi = -Infinity;
  const each = function (fn) {
    for (let j = 0; j < values.length; j++) {
      const row = values[j];
      for (let i = 0; i < row.length; i++) {
        const v = row[i];
        if (Array.isArray(v)) v.forEach(function (u, c) { fn(j, i, c, u); }); else fn(j, i, 0, v);
      }
    }
  };
  each(function (j, i, c, v) { if (v !== null && isFinite(v)) { lo = Math.min(lo, v); hi = Math.max(hi, v); } });
  if (!isFinite(lo)) { lo = 0; hi = 1; }
  if (hi - lo < 1e-12) { hi += 0.5; lo -= 0.5; }
  const t0 = t[0], t1 = t[t.length - 1] > t0 ? t[t.length - 1] : t0 + 1;
  const X = function (s) { return left + (s - t0) / (t1 - t0) * (w - left - right); };
  const Y = function (v) { return top + (hi - v) / (hi - lo) * (h - top - bottom); };
  ctx.strokeStyle = "#ccc"; ctx.strokeRect(left, top, w - left - right, h - top - bottom);
  ctx.fillStyle = "#333"; ctx.font = "11px system-ui, sans-serif";
  ctx.fillText(name, left + 4, 12);
  ctx.fillText(hi.toPrecision(3), 2, top + 8); ctx.fillText(lo.toPrecision(3), 2, h - bottom);
  ctx.fillText(t0.toFixed(0) + " s", left, h - 4); ctx.fillText(t1.toFixed(0) + " s", w - right - 34, h - 4);
  const n = values.length ? values[0].length : 0;
  const channels = n && Array.isArray(values[0][0]) ? values[0][0].length : 1;
  for (let i = 0; i < n; i++) for (let c = 0; c < channels; c++) {
    ctx.strokeStyle = FF.color(i); ctx.lineWidth = 1.2; ctx.setLineDash(c ? [4, 3] : []);
    ctx.beginPath();
    let pen = false;
    const stride = Math.max(1, Math.floor(values.length / (2 * w)));
    for (let j = 0; j < values.length; j += stride) {
      const v = channels > 1 ? values[j][i][c] : values[j][i];
      if (v === null) { pen = false; continue; }
      if (pen) ctx.lineTo(X(t[j]), Y(v)); else ctx.moveTo(X(t[j]), Y(v));
      pen = true;
    }
    ctx.stroke();
  }
  ctx.setLineDash([]);
  ctx.strokeStyle = "#000"; ctx.lineWidth = 1;
  ctx.beginPath(); ctx.moveTo(X(tNow), top); ctx.lineTo(X(tNow), h - bottom); ctx.stroke();
};
