// The time plot beside the 3D view: the run's plotted columns (the dependent rates, or the joint
// torques of an inverse-dynamics run) against t, with a cursor at the time shown.
const colours = ['#1565c0', '#c62828', '#2e7d32', '#6a1b9a', '#ef6c00', '#00838f', '#4e342e', '#ad1457'];

export function drawPlot(canvas, run, time) {
  const dpr = window.devicePixelRatio || 1;
  const w = canvas.clientWidth, h = canvas.clientHeight;
  if (canvas.width !== Math.round(w * dpr) || canvas.height !== Math.round(h * dpr)) {
    canvas.width = Math.round(w * dpr);
    canvas.height = Math.round(h * dpr);
  }
  const g = canvas.getContext('2d');
  g.setTransform(dpr, 0, 0, dpr, 0, 0);
  g.clearRect(0, 0, w, h);
  g.font = '11px system-ui, sans-serif';
  if (!run || !run.plot || !run.plot.columns.length) {
    g.fillStyle = '#667';
    g.fillText(run ? 'this run has no plotted columns' : 'no run loaded: drag the machine', 10, 20);
    return;
  }
  const t = run.t, series = run.plot.columns.map((name) => ({ name, values: run.columns[name] }));
  let lo = Infinity, hi = -Infinity;
  for (const s of series) for (const v of s.values) if (Number.isFinite(v)) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
  if (!(hi > lo)) { lo -= 1; hi += 1; }
  const pad = (hi - lo) * 0.08; lo -= pad; hi += pad;
  const left = 58, right = 150, top = 18, bottom = 22;
  const t0 = t[0], t1 = t[t.length - 1] > t0 ? t[t.length - 1] : t0 + 1;
  const x = (v) => left + ((v - t0) / (t1 - t0)) * (w - left - right);
  const y = (v) => top + (1 - (v - lo) / (hi - lo)) * (h - top - bottom);
  g.strokeStyle = '#ccd'; g.fillStyle = '#556'; g.lineWidth = 1;
  g.strokeRect(left, top, w - left - right, h - top - bottom);
  for (let k = 0; k <= 4; ++k) {
    const v = lo + ((hi - lo) * k) / 4;
    g.fillText(Math.abs(v) >= 1e4 || (Math.abs(v) < 1e-2 && v !== 0) ? v.toExponential(1) : v.toFixed(3), 4, y(v) + 4);
  }
  g.fillText(`${t0.toFixed(2)} s`, left, h - 6);
  g.fillText(`${t1.toFixed(2)} s`, w - right - 36, h - 6);
  g.fillText(run.plot.title + (run.plot.unit ? ` (${run.plot.unit})` : ''), left + 4, 12);
  series.forEach((s, k) => {
    g.strokeStyle = colours[k % colours.length];
    g.lineWidth = 1.5;
    g.beginPath();
    const stride = Math.max(1, Math.floor(t.length / (2 * (w - left - right))));
    for (let i = 0; i < t.length; i += stride) {
      if (!Number.isFinite(s.values[i])) continue;
      if (i === 0) g.moveTo(x(t[i]), y(s.values[i])); else g.lineTo(x(t[i]), y(s.values[i]));
    }
    g.stroke();
    g.fillStyle = g.strokeStyle;
    g.fillText(s.name, w - right + 8, top + 12 + 14 * k);
  });
  g.strokeStyle = '#d32f2f'; g.lineWidth = 1.5;
  g.beginPath(); g.moveTo(x(time), top); g.lineTo(x(time), h - bottom); g.stroke();
}
