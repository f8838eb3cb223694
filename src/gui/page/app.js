"use strict";
// sweepmtf gui: the page. All numbers come from the server (the library);
// this script only draws them and sends what the user changed.
const TOKEN = "__TOKEN__";
const $ = (id) => document.getElementById(id);
const SVG = "http://www.w3.org/2000/svg";
const COLOURS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf", "#7f7f7f"];

function el(name, attrs, parent, text) {
  const e = document.createElementNS(SVG, name);
  for (const k in attrs) e.setAttribute(k, attrs[k]);
  if (text !== undefined) e.textContent = text;
  if (parent) parent.appendChild(e);
  return e;
}

async function api(path, body, raw) {
  const opts = { headers: { "X-Sweepmtf-Token": TOKEN } };
  if (body !== undefined) {
    opts.method = "POST";
    if (raw) { opts.body = body; } else { opts.body = JSON.stringify(body); opts.headers["Content-Type"] = "application/json"; }
  }
  const r = await fetch(path, opts);
  const j = await r.json();
  if (!r.ok) { const e = new Error(j.error || ("HTTP " + r.status)); e.code = j.code; throw e; }
  return j;
}

function status(text, error) {
  const s = $("status");
  s.textContent = text;
  s.className = error ? "error" : "";
}

function fmt(x, d) { return x === null || x === undefined ? "—" : Number(x).toFixed(d); }

// ---------------------------------------------------------------- axes
function niceStep(span, n) {
  const raw = span / n, p = Math.pow(10, Math.floor(Math.log10(raw))), m = raw / p;
  return (m < 1.5 ? 1 : m < 3.5 ? 2 : m < 7.5 ? 5 : 10) * p;
}

// A plot frame: returns {x(v), y(v), g} for data ranges [x0,x1] × [y0,y1].
function frame(svg, box, xr, yr, xlabel, ylabel) {
  const [L, T, W, H] = box;
  const x = (v) => L + (v - xr[0]) / (xr[1] - xr[0]) * W;
  const y = (v) => T + H - (v - yr[0]) / (yr[1] - yr[0]) * H;
  const g = el("g", {}, svg);
  const xs = niceStep(xr[1] - xr[0], 8), ys = niceStep(yr[1] - yr[0], 6);
  for (let v = Math.ceil(xr[0] / xs) * xs; v <= xr[1] + 1e-9; v += xs) {
    el("line", { x1: x(v), x2: x(v), y1: T, y2: T + H, class: "grid" }, g);
    el("text", { x: x(v), y: T + H + 15, "text-anchor": "middle", class: "tick" }, g, +v.toFixed(6));
  }
  for (let v = Math.ceil(yr[0] / ys) * ys; v <= yr[1] + 1e-9; v += ys) {
    el("line", { x1: L, x2: L + W, y1: y(v), y2: y(v), class: "grid" }, g);
    el("text", { x: L - 6, y: y(v) + 4, "text-anchor": "end", class: "tick" }, g, +v.toFixed(6));
  }
  el("rect", { x: L, y: T, width: W, height: H, fill: "none", class: "axis" }, g);
  el("text", { x: L + W / 2, y: T + H + 32, "text-anchor": "middle", class: "axis-label" }, g, xlabel);
  el("text", { x: 14, y: T + H / 2, "text-anchor": "middle", class: "axis-label", transform: `rotate(-90 14 ${T + H / 2})` }, g, ylabel);
  return { x, y, g, box };
}

function polyline(pts) { return pts.map((p, i) => (i ? "L" : "M") + p[0].toFixed(2) + "," + p[1].toFixed(2)).join(""); }

// ---------------------------------------------------------------- measure view
const M = {
  state: null, photo: null, corners: null, result: null, busy: false, pending: null,
  count: 0, drag: null, modelCut: null, charts: [],
};

function fillSelect(sel, items, value) {
  sel.innerHTML = "";
  for (const [v, label] of items) {
    const o = document.createElement("option");
    o.value = v; o.textContent = label; sel.appendChild(o);
  }
  if (value !== undefined && value !== null) sel.value = String(value);
}

async function loadState() {
  M.state = await api("/api/state");
  fillSelect($("photo"), M.state.photos.map((p) => [p.id, p.name]), M.photo ? M.photo.id : undefined);
  const targets = [["", "none (one sweep strip)"]].concat(M.state.targets.map((t) => [t.id, t.label]));
  if (!$("target").options.length) {
    fillSelect($("target"), targets, M.state.default_target === null ? "" : M.state.default_target);
    $("out-dir").value = M.state.out_dir;
    $("file").setAttribute("accept", M.state.photo_extensions.concat(M.state.raw_extensions).map((e) => "." + e).join(","));
  }
}

// Every copy of the target in the photo (/api/charts): with several, a picker
// (measure --chart-index) and their outlines on the photo.
async function findCharts() {
  M.charts = [];
  $("chart-pick").classList.add("hidden");
  if (!M.photo || $("target").value === "") return;
  const id = M.photo.id, t = $("target").value;
  try {
    const r = await api(`/api/charts?id=${id}&target=${t}`);
    if (!M.photo || M.photo.id !== id || $("target").value !== t) return;
    M.charts = r.charts;
  } catch (e) { return; }
  if (M.charts.length > 1) {
    const n = M.charts.length;
    fillSelect($("chart"), M.charts.map((c) => [c.index, `${c.index + 1} of ${n}` + (c.index === 0 ? " (leftmost)" : "")]), M.chartIndex || 0);
    $("chart-pick").classList.remove("hidden");
  }
  document.body.dataset.charts = String(M.charts.length);
  drawOverlay();
}

function showPhoto(id) {
  const p = M.state.photos.find((q) => q.id === Number(id));
  if (!p) return;
  M.photo = p; M.result = null; M.corners = null;
  const svg = $("photo-svg");
  svg.innerHTML = "";
  svg.setAttribute("viewBox", `0 0 ${p.width} ${p.height}`);
  const img = el("image", { href: `/api/display?id=${p.id}&token=${TOKEN}`, x: 0, y: 0, width: p.width, height: p.height, preserveAspectRatio: "none", id: "photo-image" }, svg);
  img.addEventListener("load", () => { document.body.dataset.photoShown = String(p.id); status(`${p.name}: ${p.width}×${p.height} px`); }, { once: true });
  el("g", { id: "overlay" }, svg);
  $("stage").classList.add("has-photo");
  drawMagnifierImage();
  M.chartIndex = 0;
  if ($("target").value !== "") { measure(null); findCharts(); } else { M.charts = []; $("chart-pick").classList.add("hidden"); defaultCorners(); drawOverlay(); }
}

function defaultCorners() {
  const p = M.photo, w = p.width, h = p.height;
  M.corners = [[w * 0.2, h * 0.4], [w * 0.8, h * 0.4], [w * 0.8, h * 0.6], [w * 0.2, h * 0.6]];
}

function options() {
  const o = {
    photo: M.photo.id,
    target: $("target").value === "" ? null : Number($("target").value),
    refine: $("refine").checked,
    out_dir: $("out-dir").value,
  };
  for (const k of ["method", "channel", "sweep"]) {
    const v = $(k).value;
    if (v !== $(k).options[0].value) o[k] = v;
  }
  if ($("pitch").value.trim() !== "") o.pixel_pitch = $("pitch").value.trim();
  return o;
}

// Measures with the current corners (or none: found from the target); one request at a time, the latest wins.
async function measure(corners) {
  if (!M.photo) return;
  const req = options();
  req.roi = corners;
  if (!corners && M.charts.length > 1) req.chart_index = M.chartIndex || 0;
  if (M.busy) { M.pending = req; return; }
  M.busy = true;
  document.body.dataset.state = "busy";
  let next = req;
  while (next) {
    M.pending = null;
    const t0 = performance.now();
    try {
      status("measuring…");
      const r = await api("/api/measure", next);
      M.result = r; M.corners = r.roi;
      M.count += 1;
      const ms = performance.now() - t0;
      document.body.dataset.measureCount = String(M.count);
      document.body.dataset.lastMs = ms.toFixed(1);
      status(`${r.name}: measured in ${r.measure_ms.toFixed(0)} ms (round trip ${ms.toFixed(0)} ms)`);
      $("warnings").innerHTML = "";
      for (const w of r.warnings) { const li = document.createElement("li"); li.textContent = w; $("warnings").appendChild(li); }
      for (const n of r.notes || []) { const li = document.createElement("li"); li.className = "note"; li.textContent = n; $("warnings").appendChild(li); }
    } catch (e) {
      M.result = null;
      if (!M.corners) defaultCorners();
      M.count += 1;
      document.body.dataset.measureCount = String(M.count);
      status(e.message, true);
      $("warnings").innerHTML = "";
      const li = document.createElement("li"); li.className = "error"; li.textContent = e.message; $("warnings").appendChild(li);
    }
    drawOverlay(); drawMtf(); drawFigures();
    $("command").textContent = M.result ? M.result.command : "";
    if ($("overlay").checked) await overlayModel();
    next = M.pending;
  }
  M.busy = false;
  document.body.dataset.state = "ready";
}

function drawOverlay() {
  const g = $("overlay");
  if (!g || !M.photo) return;
  g.innerHTML = "";
  const s = M.photo.width / Math.max(1, $("photo-svg").clientWidth || M.photo.display_width);
  const lw = 1.5 * s;
  if (M.result) {
    for (const c of M.result.curves) {
      // Through a lens model the binned region's edges are curves (outline_px).
      const outline = c.outline_px && c.outline_px.length ? c.outline_px : c.region_px;
      el("polygon", { points: outline.map((p) => p.join(",")).join(" "), class: "binned", "stroke-width": lw }, g);
      // The paper read for a camera tone curve's black level (paper_bands_px).
      for (const b of c.paper_bands_px || []) el("polygon", { points: b.map((p) => p.join(",")).join(" "), class: "paper-band", "stroke-width": lw }, g);
      for (const l of c.measured_lines_px) el("line", { x1: l[0][0], y1: l[0][1], x2: l[1][0], y2: l[1][1], class: "measured-line", "stroke-width": lw }, g);
      if (c.alias_line_px) { const l = c.alias_line_px; el("line", { x1: l[0][0], y1: l[0][1], x2: l[1][0], y2: l[1][1], class: "alias-line", "stroke-width": 2 * lw }, g); }
    }
  }
  for (const c of M.charts.length > 1 ? M.charts : []) {
    el("polygon", { points: c.corners_px.map((p) => p.join(",")).join(" "), class: "other-chart", "stroke-width": lw }, g);
    const top = c.corners_px.reduce((a, p) => (p[1] < a[1] ? p : a));
    el("text", { x: top[0], y: top[1] - 8 * s, class: "corner-label", "font-size": 16 * s }, g, `chart ${c.index + 1}`);
  }
  if (!M.corners) return;
  el("polygon", { points: M.corners.map((p) => p.join(",")).join(" "), class: "roi", "stroke-width": lw }, g);
  M.corners.forEach((p, i) => {
    const c = el("circle", { cx: p[0], cy: p[1], r: 9 * s, class: "corner", "stroke-width": lw, "data-corner": i, id: "corner-" + i }, g);
    el("text", { x: p[0] + 11 * s, y: p[1] - 11 * s, class: "corner-label", "font-size": 14 * s }, g, String(i + 1));
    c.addEventListener("pointerdown", startDrag);
  });
}

function svgPoint(evt) {
  const svg = $("photo-svg");
  const pt = svg.createSVGPoint();
  pt.x = evt.clientX; pt.y = evt.clientY;
  return pt.matrixTransform(svg.getScreenCTM().inverse());
}

function startDrag(evt) {
  evt.preventDefault();
  const i = Number(evt.target.dataset.corner);
  const p = svgPoint(evt);
  M.drag = { i, dx: M.corners[i][0] - p.x, dy: M.corners[i][1] - p.y, target: evt.target };
  evt.target.setPointerCapture(evt.pointerId);
  evt.target.classList.add("dragging");
  evt.target.addEventListener("pointermove", moveDrag);
  evt.target.addEventListener("pointerup", endDrag, { once: true });
  showMagnifier(M.corners[i], evt);
}

function moveDrag(evt) {
  if (!M.drag) return;
  const p = svgPoint(evt);
  const c = [Math.round((p.x + M.drag.dx) * 4) / 4, Math.round((p.y + M.drag.dy) * 4) / 4];
  M.corners[M.drag.i] = c;
  const t = M.drag.target;
  t.setAttribute("cx", c[0]); t.setAttribute("cy", c[1]);
  const poly = $("overlay").querySelector(".roi");
  if (poly) poly.setAttribute("points", M.corners.map((q) => q.join(",")).join(" "));
  showMagnifier(c, evt);
}

function endDrag(evt) {
  const t = M.drag && M.drag.target;
  if (t) { t.removeEventListener("pointermove", moveDrag); t.classList.remove("dragging"); }
  M.drag = null;
  $("magnifier").classList.add("hidden");
  measure(M.corners.map((c) => [c[0], c[1]]));
}

// The magnifier: the photo's own pixels around the corner, 6 screen pixels
// per image pixel. The display rendition is drawn first (at once); the
// full-resolution window (/api/crop, 64 px around the corner) over it as soon
// as it arrives, and again when the corner leaves its middle. The corner's
// position is kept to 0.25 px.
function drawMagnifierImage() {
  const m = $("magnifier"), p = M.photo;
  m.innerHTML = "";
  M.crop = { at: null, busy: false, want: null };
  el("image", { href: `/api/display?id=${p.id}&token=${TOKEN}`, x: 0, y: 0, width: p.width, height: p.height, preserveAspectRatio: "none" }, m);
  el("image", { id: "mag-full", preserveAspectRatio: "none", width: 0, height: 0 }, m);
  el("line", { id: "mag-h", stroke: "#fc3" }, m);
  el("line", { id: "mag-v", stroke: "#fc3" }, m);
}

async function fetchCrop(c) {
  const k = M.crop;
  if (!k) return;
  if (k.busy) { k.want = c; return; }
  if (k.at && Math.abs(c[0] - k.at[0]) < 12 && Math.abs(c[1] - k.at[1]) < 12) return;
  k.busy = true; k.want = null;
  try {
    const r = await fetch(`/api/crop?id=${M.photo.id}&x=${c[0]}&y=${c[1]}&token=${TOKEN}`);
    if (r.ok) {
      const v = await r.json();
      const im = $("mag-full");
      if (im) { im.setAttribute("href", v.png); im.setAttribute("x", v.x); im.setAttribute("y", v.y); im.setAttribute("width", v.width); im.setAttribute("height", v.height); }
      k.at = c;
      document.body.dataset.cropCount = String(Number(document.body.dataset.cropCount || 0) + 1);
    }
  } finally {
    k.busy = false;
  }
  if (k.want) fetchCrop(k.want);
}

function showMagnifier(c, evt) {
  const m = $("magnifier"), stage = $("stage").getBoundingClientRect();
  const span = 180 / 6;
  fetchCrop(c);
  m.setAttribute("viewBox", `${c[0] - span / 2} ${c[1] - span / 2} ${span} ${span}`);
  const h = $("mag-h"), v = $("mag-v");
  h.setAttribute("x1", c[0] - span); h.setAttribute("x2", c[0] + span); h.setAttribute("y1", c[1]); h.setAttribute("y2", c[1]);
  v.setAttribute("y1", c[1] - span); v.setAttribute("y2", c[1] + span); v.setAttribute("x1", c[0]); v.setAttribute("x2", c[0]);
  h.setAttribute("stroke-width", span / 180); v.setAttribute("stroke-width", span / 180);
  let left = evt.clientX - stage.left + 30, top = evt.clientY - stage.top - 210;
  if (left + 190 > stage.width) left = evt.clientX - stage.left - 210;
  if (top < 0) top = evt.clientY - stage.top + 30;
  m.style.left = left + "px"; m.style.top = top + "px";
  m.classList.remove("hidden");
}

function drawMtf() {
  const svg = $("mtf-plot");
  svg.innerHTML = "";
  const r = M.result;
  let fmax = 0.55, ymax = 1.1;
  if (r) for (const c of r.curves) for (const p of c.points) { fmax = Math.max(fmax, p.freq_cy_px * 1.04); ymax = Math.max(ymax, Math.min(1.6, p.mtf + p.mtf_err + 0.05)); }
  const pitch = r ? r.pixel_pitch_mm : null;
  const xl = pitch ? `cycles/pixel (× ${fmt(1 / pitch, 1)} = lp/mm)` : "cycles/pixel";
  const f = frame(svg, [56, 14, 560, 310], [0, fmax], [0, ymax], xl, "MTF");
  const clip = el("clipPath", { id: "plot-clip" }, el("defs", {}, svg));
  el("rect", { x: 56, y: 14, width: 560, height: 310 }, clip);
  const g = el("g", { "clip-path": "url(#plot-clip)" }, svg);
  el("line", { x1: f.x(0.5), x2: f.x(0.5), y1: 14, y2: 324, class: "nyquist" }, g);
  el("text", { x: f.x(0.5) + 4, y: 28, class: "tick", fill: "#c33" }, svg, "Nyquist");
  if (!r) return;
  r.curves.forEach((c, k) => {
    const col = COLOURS[k % COLOURS.length];
    const pts = c.points;
    const up = pts.map((p) => [f.x(p.freq_cy_px), f.y(p.mtf + p.mtf_err)]);
    const dn = pts.map((p) => [f.x(p.freq_cy_px), f.y(Math.max(0, p.mtf - p.mtf_err))]).reverse();
    el("path", { d: polyline(up.concat(dn)) + "Z", class: "band", fill: col, "fill-opacity": 0.18 }, g);
    el("path", { d: polyline(pts.filter((p) => !p.aliased).map((p) => [f.x(p.freq_cy_px), f.y(p.mtf)])), fill: "none", stroke: col, "stroke-width": 2, class: "mtf-line" }, g);
    for (const p of pts) if (p.aliased) el("circle", { cx: f.x(p.freq_cy_px), cy: f.y(p.mtf), r: 2.5, fill: "none", stroke: "#d00", class: "aliased" }, g);
    for (const p of pts) if (p.jpeg_limited && !p.aliased) el("circle", { cx: f.x(p.freq_cy_px), cy: f.y(p.mtf), r: 3, fill: "none", stroke: col, class: "jpeg-limited" }, g);
    for (const [key, lv] of [["mtf50_cy_px", 0.5], ["mtf10_cy_px", 0.1]]) {
      const v = c.figures[key];
      if (v === null || v === undefined) continue;
      el("path", { d: `M${f.x(0)},${f.y(lv)}L${f.x(v)},${f.y(lv)}L${f.x(v)},${f.y(0)}`, stroke: col, fill: "none", class: "mark" }, g);
    }
    if (r.curves.length > 1) el("text", { x: 606, y: 40 + 14 * k, "text-anchor": "end", class: "legend", fill: col }, svg, `${c.channel}/${c.sweep_id}`);
  });
  let row = r.curves.length > 1 ? r.curves.length : 0;
  if (M.modelCut && pitch) {
    const mc = M.modelCut;
    el("path", { d: polyline(mc.freq_cy_mm.map((fm, i) => [f.x(fm * pitch), f.y(mc.mtf[i])])), fill: "none", stroke: "#555", "stroke-dasharray": "7 4", "stroke-width": 1.5, class: "model-line" }, g);
    el("text", { x: 606, y: 40 + 14 * row++, "text-anchor": "end", class: "legend", fill: "#555" }, svg, "-- model");
  }
  if (r.curves.some((c) => c.points.some((p) => p.aliased))) el("text", { x: 606, y: 40 + 14 * row++, "text-anchor": "end", class: "legend", fill: "#d00" }, svg, "○ aliased (not an MTF)");
  if (r.curves.some((c) => c.points.some((p) => p.jpeg_limited && !p.aliased))) el("text", { x: 606, y: 40 + 14 * row, "text-anchor": "end", class: "legend", fill: "#333" }, svg, "○ JPEG-limited (the file's, not the lens's)");
}

function drawFigures() {
  const t = $("figures");
  t.innerHTML = "";
  const r = M.result;
  if (!r) return;
  const row = (cells, head) => { const tr = document.createElement("tr"); cells.forEach((c, i) => { const td = document.createElement(i === 0 || head ? "th" : "td"); td.textContent = c; tr.appendChild(td); }); t.appendChild(tr); return tr; };
  const pitch = r.pixel_pitch_mm;
  // One row per curve: MTF50 (cy/px, lp/mm, LW/PH), MTF10, MTF at Nyquist, chart modulation.
  row(["", "MTF50 cy/px"].concat(pitch ? ["lp/mm"] : [], ["LW/PH", "MTF10 cy/px", "at Nyquist", "chart mod."]), true);
  const reached = (v, d) => (v ? fmt(v.cy_px, d) : "not reached");
  r.summary.curves.forEach((s, k) => {
    const c = r.curves[k];
    const name = r.curves.length > 1 ? `${c.channel}/${c.sweep_id}` : c.channel;
    const v = s.mtf50;
    // MTF50 with its one-sigma uncertainty where the summary gives one.
    const f50 = v && v.err_cy_px !== undefined && v.err_cy_px !== null ? `${fmt(v.cy_px, 4)} ± ${fmt(v.err_cy_px, 4)}` : reached(v, 4);
    const cells = [name, f50].concat(pitch ? [v && v.cy_mm !== undefined ? fmt(v.cy_mm, 1) : ""] : [],
      [v ? fmt(v.lw_ph, 0) : "", reached(s.mtf10, 4), fmt(c.figures.mtf_nyquist, 3), fmt(c.chart_modulation, 3)]);
    const tr = row(cells);
    tr.id = `mtf50-${k}`;
    if (v) tr.dataset.cyPx = String(v.cy_px);
    tr.lastChild.title = c.chart_modulation_source;
  });
  if (pitch) { const tr = row(["pixel pitch", `${fmt(pitch * 1000, 3)} µm`]); tr.lastChild.colSpan = 6; tr.lastChild.style.textAlign = "left"; }
}

async function save() {
  if (!M.photo) return;
  const req = options();
  req.roi = M.result ? M.result.roi : M.corners;
  try {
    const r = await api("/api/save", req);
    $("saved").textContent = "written: " + r.written.join(", ");
    $("saved").dataset.count = String((Number($("saved").dataset.count) || 0) + 1);
    $("command").textContent = r.command;
  } catch (e) {
    $("saved").textContent = e.message;
    status(e.message, true);
  }
}

async function copyCommand() {
  const text = $("command").textContent;
  try { await navigator.clipboard.writeText(text); status("command copied"); } catch (e) {
    const range = document.createRange(); range.selectNodeContents($("command"));
    const sel = window.getSelection(); sel.removeAllRanges(); sel.addRange(range);
    status("command selected: copy it with Ctrl-C");
  }
}

async function upload(file) {
  if (file.size > M.state.max_upload_bytes) { status(`${file.name}: larger than the ${M.state.max_upload_bytes >> 20} MiB upload limit`, true); return; }
  status(`reading ${file.name}…`);
  try {
    const p = await api("/api/upload?name=" + encodeURIComponent(file.name), file, true);
    await loadState();
    $("photo").value = String(p.id);
    showPhoto(p.id);
  } catch (e) { status(e.message, true); }
}

async function overlayModel() {
  M.modelCut = null;
  const r = M.result;
  if (!r || !r.pixel_pitch_mm || !$("overlay").checked) { drawMtf(); return; }
  let fmax = 0.55;
  for (const c of r.curves) for (const p of c.points) fmax = Math.max(fmax, p.freq_cy_px * 1.04);
  try {
    const j = await api("/api/model", { factors: modelFactors(), cut: "u", f_max: fmax / r.pixel_pitch_mm, points: 301, map_size: 0 });
    M.modelCut = j.cut;
  } catch (e) { status("model: " + e.message, true); }
  drawMtf();
}

function initMeasure() {
  $("photo").addEventListener("change", () => showPhoto($("photo").value));
  $("file").addEventListener("change", (e) => { if (e.target.files[0]) upload(e.target.files[0]); });
  const stage = $("stage");
  stage.addEventListener("dragover", (e) => { e.preventDefault(); stage.classList.add("drag-over"); });
  stage.addEventListener("dragleave", () => stage.classList.remove("drag-over"));
  stage.addEventListener("drop", (e) => { e.preventDefault(); stage.classList.remove("drag-over"); if (e.dataTransfer.files[0]) upload(e.dataTransfer.files[0]); });
  $("target").addEventListener("change", () => { if (M.photo) { M.chartIndex = 0; if ($("target").value !== "") { measure(null); findCharts(); } else { M.charts = []; $("chart-pick").classList.add("hidden"); defaultCorners(); M.result = null; drawOverlay(); drawMtf(); drawFigures(); } } });
  $("chart").addEventListener("change", () => { M.chartIndex = Number($("chart").value); measure(null); });
  $("locate").addEventListener("click", () => measure(null));
  for (const id of ["method", "channel", "sweep", "pitch", "refine"]) $(id).addEventListener("change", () => { if (M.photo && (M.result || $("target").value === "")) measure(M.corners ? M.corners.map((c) => [c[0], c[1]]) : null); });
  $("overlay").addEventListener("change", overlayModel);
  $("save").addEventListener("click", save);
  $("copy").addEventListener("click", copyCommand);
  window.addEventListener("resize", drawOverlay);
}

// ---------------------------------------------------------------- model view
// Each factor: its `model` flag, shapes with parameters (value, unit), and the spec they make.
const FACTORS = [
  { kind: "optics", label: "Diffraction", on: true, shapes: { diffraction: [["lambda", 550, "nm", 380, 1100, 5], ["fnum", 4, "", 0.7, 32, 0.1]] } },
  { kind: "aperture", label: "Pixel aperture", on: true, shapes: {
      rect: [["A", 4.3, "um", 0.5, 20, 0.1], ["B", 4.3, "um", 0.5, 20, 0.1]],
      L: [["A", 5, "um", 0.5, 20, 0.1], ["B", 5, "um", 0.5, 20, 0.1], ["a", 2.5, "um", 0.1, 20, 0.1], ["b", 2.5, "um", 0.1, 20, 0.1]],
      rhomb: [["A", 5, "um", 0.5, 20, 0.1], ["B", 5, "um", 0.5, 20, 0.1]],
      hex: [["D", 5, "um", 0.5, 20, 0.1]], oct: [["D", 5, "um", 0.5, 20, 0.1]], circle: [["D", 4.3, "um", 0.5, 20, 0.1]] } },
  { kind: "sampling", label: "Sampling grid", on: true, shapes: {
      rect: [["px", 4.3, "um", 0.5, 20, 0.1], ["py", 4.3, "um", 0.5, 20, 0.1]],
      hex: [["pitch", 5, "um", 0.5, 20, 0.1], ["rows", "x", "", ["x", "y"]]] } },
  { kind: "diffusion", label: "Carrier diffusion", on: false, shapes: { "": [["lambda", 550, "nm", 250, 1100, 5], ["depletion", 2, "um", 0, 20, 0.1], ["length", 10, "um", 0.1, 100, 0.1]] } },
  { kind: "cte", label: "Charge transfer", on: false, shapes: { "": [["n", 2000, "", 1, 10000, 1], ["cti", 0.00001, "", 0, 0.001, 0.000001], ["pitch", 4.3, "um", 0.5, 20, 0.1], ["model", "exp", "", ["exp", "exact"]], ["axis", "u", "", ["u", "v"]]] } },
  { kind: "olpf", label: "OLPF", on: false, shapes: { "4spot": [["d", 4.3, "um", 0, 20, 0.1]], "2spot": [["d", 4.3, "um", 0, 20, 0.1], ["axis", "u", "", ["u", "v"]]] } },
  { kind: "gaussian", label: "Gaussian blur", on: false, shapes: { "": [["sigma", 1, "um", 0, 20, 0.05]] } },
  { kind: "defocus", label: "Defocus", on: false, shapes: {
      wave: [["lambda", 550, "nm", 380, 1100, 5], ["fnum", 4, "", 0.7, 32, 0.1], ["w020", 0.25, "", 0, 5, 0.01]],
      geometric: [["blur", 10, "um", 0, 200, 0.5]] } },
];

const MODEL = { busy: false, again: false, count: 0 };

function buildFactorControls() {
  const box = $("factors");
  FACTORS.forEach((f, fi) => {
    const div = document.createElement("div");
    div.className = "factor" + (f.on ? "" : " off");
    div.id = "factor-" + f.kind;
    const head = document.createElement("div"); head.className = "head";
    const cb = document.createElement("input"); cb.type = "checkbox"; cb.checked = f.on; cb.id = `on-${f.kind}`;
    cb.addEventListener("change", () => { f.on = cb.checked; div.classList.toggle("off", !f.on); modelChanged(); });
    head.appendChild(cb);
    const lab = document.createElement("label"); lab.htmlFor = cb.id; lab.textContent = `${f.label} (--${f.kind})`; head.appendChild(lab);
    const shapes = Object.keys(f.shapes);
    f.shape = shapes[0];
    f.values = {};
    for (const s of shapes) { f.values[s] = {}; for (const p of f.shapes[s]) f.values[s][p[0]] = p[1]; }
    const params = document.createElement("div"); params.className = "params";
    const render = () => {
      params.innerHTML = "";
      for (const p of f.shapes[f.shape]) {
        const [k, , unit, min, max, step] = p;
        const name = document.createElement("span"); name.textContent = unit ? `${k} (${unit === "um" ? "µm" : unit})` : k;
        params.appendChild(name);
        if (Array.isArray(min)) {
          const sel = document.createElement("select");
          for (const o of min) { const op = document.createElement("option"); op.textContent = o; sel.appendChild(op); }
          sel.value = f.values[f.shape][k];
          sel.addEventListener("change", () => { f.values[f.shape][k] = sel.value; modelChanged(); });
          params.appendChild(sel); params.appendChild(document.createElement("span"));
          continue;
        }
        const range = document.createElement("input"); range.type = "range"; range.min = min; range.max = max; range.step = step; range.value = f.values[f.shape][k];
        range.id = `p-${f.kind}-${k}`;
        const num = document.createElement("input"); num.type = "number"; num.min = min; num.max = max; num.step = step; num.value = f.values[f.shape][k];
        range.addEventListener("input", () => { num.value = range.value; f.values[f.shape][k] = Number(range.value); modelChanged(); });
        num.addEventListener("input", () => { range.value = num.value; f.values[f.shape][k] = Number(num.value); modelChanged(); });
        params.appendChild(range); params.appendChild(num);
      }
    };
    if (shapes.length > 1 || shapes[0] !== "" && f.kind !== "optics") {
      const sel = document.createElement("select");
      for (const s of shapes) { const o = document.createElement("option"); o.textContent = s; sel.appendChild(o); }
      sel.addEventListener("change", () => { f.shape = sel.value; render(); modelChanged(); });
      head.appendChild(sel);
    }
    render();
    div.appendChild(head); div.appendChild(params);
    box.appendChild(div);
    FACTORS[fi].div = div;
  });
}

function specOf(f) {
  const parts = f.shapes[f.shape].map((p) => `${p[0]}=${f.values[f.shape][p[0]]}${p[2]}`);
  return (f.shape ? f.shape + ":" : "") + parts.join(",");
}

function modelFactors() {
  const out = FACTORS.filter((f) => f.on).map((f) => ({ kind: f.kind, spec: specOf(f) }));
  for (const line of $("extra").value.split("\n")) {
    const t = line.trim();
    if (!t || t.startsWith("#")) continue;
    const i = t.search(/\s/);
    if (i > 0) out.push({ kind: t.slice(0, i), spec: t.slice(i).trim() });
    else out.push({ kind: t, spec: "" });
  }
  return out;
}

function modelChanged() {
  $("fmax-out").textContent = $("fmax").value;
  const fs = modelFactors();
  const q = (s) => /^[\w.,:=;+-]+$/.test(s) ? s : `'${s.replace(/'/g, "'\\''")}'`;
  $("model-command").textContent = "sweepmtf model " + fs.map((f) => `--${f.kind} ${q(f.spec)}`).join(" ") + ` --cut ${$("cut-dir").value} --f-max ${$("fmax").value} -o cut.csv`;
  if (MODEL.busy) { MODEL.again = true; return; }
  runModel();
}

async function runModel() {
  MODEL.busy = true;
  do {
    MODEL.again = false;
    const size = Number($("map-size").value);
    const req = { factors: modelFactors(), cut: $("cut-dir").value, f_max: Number($("fmax").value), points: 401, map_size: size };
    const t0 = performance.now();
    try {
      const j = await api("/api/model", req);
      const t1 = performance.now();
      drawCut(j);
      await drawMap(j);
      MODEL.count += 1;
      document.body.dataset.modelCount = String(MODEL.count);
      document.body.dataset.modelMs = (performance.now() - t0).toFixed(1);
      status(`model: cut ${j.cut_ms.toFixed(1)} ms` + (j.map ? `, ${j.map.size}² map ${j.map_ms.toFixed(0)} ms` : "") + `; round trip ${(t1 - t0).toFixed(0)} ms, drawn ${(performance.now() - t0).toFixed(0)} ms`);
    } catch (e) {
      status(e.message, true);
      MODEL.count += 1;
      document.body.dataset.modelCount = String(MODEL.count);
    }
  } while (MODEL.again);
  MODEL.busy = false;
  if ($("overlay").checked && M.result) overlayModel();
}

function drawCut(j) {
  const svg = $("cut-plot");
  svg.innerHTML = "";
  const c = j.cut, fm = Number($("fmax").value);
  const f = frame(svg, [56, 14, 560, 290], [0, fm], [0, 1.05], `spatial frequency along ${c.direction} (lp/mm)`, "MTF");
  const line = (vals) => polyline(c.freq_cy_mm.map((x, i) => [f.x(x), f.y(vals[i])]));
  c.factors.forEach((fa, k) => {
    const col = COLOURS[(k + 1) % COLOURS.length];
    el("path", { d: line(fa.mtf), fill: "none", stroke: col, "stroke-width": 1.2, "stroke-dasharray": "6 3" }, svg);
    el("text", { x: 606, y: 32 + 14 * k, "text-anchor": "end", class: "legend", fill: col }, svg, fa.name);
  });
  el("path", { d: line(c.mtf), fill: "none", stroke: "#000", "stroke-width": 2.2, id: "cut-total" }, svg);
  // MTF50 of the total, read off the drawn samples (for the eye and the tests).
  let f50 = null;
  for (let i = 1; i < c.mtf.length; i++) if (c.mtf[i - 1] >= 0.5 && c.mtf[i] < 0.5) { const a = c.mtf[i - 1], b = c.mtf[i]; f50 = c.freq_cy_mm[i - 1] + (a - 0.5) / (a - b) * (c.freq_cy_mm[i] - c.freq_cy_mm[i - 1]); break; }
  svg.dataset.mtf50 = f50 === null ? "" : String(f50);
  el("text", { x: 606, y: 32 + 14 * c.factors.length, "text-anchor": "end", class: "legend", fill: "#000", "font-weight": "bold" }, svg,
    "total, MTF50 " + (f50 === null ? "beyond the cut" : `${f50.toFixed(1)} lp/mm`));
  if (c.nyquist_cy_mm !== null && c.nyquist_cy_mm <= fm) {
    el("line", { x1: f.x(c.nyquist_cy_mm), x2: f.x(c.nyquist_cy_mm), y1: 14, y2: 304, class: "nyquist" }, svg);
    el("text", { x: f.x(c.nyquist_cy_mm) + 4, y: 28, class: "tick", fill: "#c33" }, svg, `Nyquist ${c.nyquist_cy_mm.toFixed(1)}`);
  }
}

function drawMap(j) {
  const svg = $("map-plot");
  svg.innerHTML = "";
  if (!j.map) { svg.classList.add("hidden"); return Promise.resolve(); }
  svg.classList.remove("hidden");
  const m = j.map, F = m.f_max_cy_mm;
  const f = frame(svg, [70, 14, 480, 480], [-F, F], [-F, F], "u (lp/mm)", "v (lp/mm)");
  const img = el("image", { href: "data:image/png;base64," + m.png_base64, x: 70, y: 14, width: 480, height: 480, preserveAspectRatio: "none" });
  f.g.insertBefore(img, f.g.querySelector("rect"));
  if (m.nyquist_cy_mm) {
    const [nu, nv] = m.nyquist_cy_mm;
    el("rect", { x: f.x(-nu), y: f.y(nv), width: f.x(nu) - f.x(-nu), height: f.y(-nv) - f.y(nv), fill: "none", stroke: "#fff", "stroke-dasharray": "6 4" }, svg);
  }
  // Colour bar (viridis, as the server's map).
  const stops = ["#440154", "#472d7b", "#3b528b", "#2c728e", "#21918c", "#28ae80", "#5ec962", "#addc30", "#fde725"];
  const grad = el("linearGradient", { id: "vir", x1: 0, y1: 1, x2: 0, y2: 0 }, el("defs", {}, svg));
  stops.forEach((s, i) => el("stop", { offset: i / (stops.length - 1), "stop-color": s }, grad));
  el("rect", { x: 575, y: 14, width: 18, height: 480, fill: "url(#vir)", stroke: "#444" }, svg);
  for (let v = 0; v <= 1.0001; v += 0.25) el("text", { x: 598, y: 14 + 480 * (1 - v) + 4, class: "tick" }, svg, v.toFixed(2));
  return new Promise((res) => { img.addEventListener("load", res, { once: true }); img.addEventListener("error", res, { once: true }); setTimeout(res, 2000); });
}

function systemToml() {
  const lines = ["name = \"sweepmtf gui\"", ""];
  for (const f of modelFactors()) lines.push("[[factor]]", `kind = "${f.kind}"`, `spec = "${f.spec.replace(/"/g, "\\\"")}"`, "");
  return lines.join("\n");
}

function initModel() {
  buildFactorControls();
  for (const id of ["cut-dir", "fmax", "map-size"]) $(id).addEventListener("input", modelChanged);
  $("extra").addEventListener("input", modelChanged);
  $("system-save").addEventListener("click", () => {
    const a = document.createElement("a");
    a.href = URL.createObjectURL(new Blob([systemToml()], { type: "text/plain" }));
    a.download = "system.toml"; a.click();
  });
  $("system-file").addEventListener("change", async (e) => {
    const file = e.target.files[0];
    if (!file) return;
    const text = await file.text();
    // [[factor]] tables: kind and spec lines (the server checks them as `model --system` does).
    const out = [];
    let kind = null;
    for (const line of text.split("\n")) {
      const k = line.match(/^\s*kind\s*=\s*"([^"]*)"/), s = line.match(/^\s*spec\s*=\s*"((?:[^"\\]|\\.)*)"/);
      if (k) kind = k[1];
      if (s && kind) { out.push(`${kind} ${s[1]}`); kind = null; }
    }
    for (const f of FACTORS) { f.on = false; document.getElementById(`on-${f.kind}`).checked = false; f.div.classList.add("off"); }
    $("extra").value = out.join("\n");
    modelChanged();
  });
}

// ---------------------------------------------------------------- batch view
// A `sweepmtf batch` output folder: its overview pictures, its summary table
// (click a heading to sort, a row to see that shot's plot and region).
const B = { data: null, sort: null, desc: false, picked: null };
const BATCH_COLUMNS = [
  ["file", "file", "l"], ["status", "status", "l"], ["mtf50_cy_px", "MTF50 cy/px"], ["mtf50p_cy_px", "MTF50P cy/px"],
  ["mtf10_cy_px", "MTF10 cy/px"], ["mtf_peak", "peak"], ["mtf_nyquist", "at Nyquist"], ["f_number", "f/"],
  ["focal_length_mm", "mm"], ["iso", "ISO"], ["lens", "lens", "l"], ["run_time_s", "s"], ["warnings", "error / warnings", "l"],
];

function batchFile(name) {
  return `/api/batch/file?dir=${encodeURIComponent(B.data.dir)}&name=${encodeURIComponent(name)}&token=${TOKEN}`;
}

async function openBatch() {
  const dir = $("batch-dir").value.trim();
  if (!dir) return;
  try {
    B.data = await api(`/api/batch?dir=${encodeURIComponent(dir)}`);
  } catch (e) { status(e.message, true); B.data = null; $("batch-table").innerHTML = ""; $("batch-pictures").innerHTML = ""; return; }
  B.picked = null; B.sort = null;
  const pics = $("batch-pictures");
  pics.innerHTML = "";
  for (const p of B.data.pictures) { const im = document.createElement("img"); im.src = batchFile(p); im.alt = p; pics.appendChild(im); }
  const ok = B.data.rows.filter((r) => r[B.data.columns.indexOf("status")] === "ok").length;
  $("batch-count").textContent = `${B.data.rows.length} shots, ${ok} measured`;
  status(`${B.data.dir}: ${B.data.rows.length} shots`);
  drawBatchTable();
  document.body.dataset.batchRows = String(B.data.rows.length);
}

function drawBatchTable() {
  const t = $("batch-table"), d = B.data;
  t.innerHTML = "";
  if (!d) return;
  const col = (name) => d.columns.indexOf(name);
  // Columns the folder has, leaving out those empty in every row (no EXIF, no lens).
  const cols = BATCH_COLUMNS.filter(([k]) => col(k) >= 0 && (k === "file" || k === "warnings" || d.rows.some((r) => r[col(k)] !== "")));
  const rows = d.rows.slice();
  if (B.sort) {
    const k = col(B.sort);
    const num = (v) => (v === "" ? NaN : Number(v));
    rows.sort((a, b) => {
      const x = num(a[k]), y = num(b[k]);
      const c = !isNaN(x) && !isNaN(y) ? x - y : isNaN(x) !== isNaN(y) ? (isNaN(x) ? 1 : -1) : String(a[k]).localeCompare(String(b[k]));
      return B.desc ? -c : c;
    });
  }
  const head = document.createElement("tr");
  for (const [k, label, cls] of cols) {
    const th = document.createElement("th");
    th.textContent = label + (B.sort === k ? (B.desc ? " ▼" : " ▲") : "");
    if (cls) th.className = cls;
    th.addEventListener("click", () => { B.desc = B.sort === k ? !B.desc : false; B.sort = k; drawBatchTable(); });
    head.appendChild(th);
  }
  const thead = document.createElement("thead"); thead.appendChild(head); t.appendChild(thead);
  const body = document.createElement("tbody");
  for (const r of rows) {
    const tr = document.createElement("tr");
    const stem = r[col("stem")];
    if (r[col("status")] !== "ok") tr.className = "error";
    if (stem === B.picked) tr.classList.add("picked");
    tr.dataset.stem = stem;
    for (const [k, , cls] of cols) {
      const td = document.createElement("td");
      let v = r[col(k)];
      if (k === "warnings" && r[col("status")] !== "ok") v = r[col("error")];
      const n = Number(v);
      td.textContent = v !== "" && !isNaN(n) && /cy_px|peak|nyquist/.test(k) ? n.toFixed(4) : v;
      if (cls) td.className = cls;
      if (k === "warnings") { td.classList.add("w"); td.title = v; }
      tr.appendChild(td);
    }
    tr.addEventListener("click", () => showShot(stem, r[col("file")], r[col("status")] === "ok"));
    body.appendChild(tr);
  }
  t.appendChild(body);
}

function showShot(stem, file, ok) {
  B.picked = stem;
  $("shot-name").textContent = ok ? file : `${file}: not measured`;
  for (const [id, name] of [["shot-mtf", `shots/${stem}.mtf.png`], ["shot-roi", `shots/${stem}.roi.png`]]) {
    const im = $(id);
    im.classList.toggle("hidden", !ok);
    if (ok) { im.onload = () => { document.body.dataset.shotShown = stem; }; im.src = batchFile(name); }
  }
  drawBatchTable();
}

function initBatch() {
  $("batch-open").addEventListener("click", openBatch);
  $("batch-dir").addEventListener("keydown", (e) => { if (e.key === "Enter") openBatch(); });
}

// ---------------------------------------------------------------- start
function showView(name) {
  for (const v of ["measure", "model", "batch"]) {
    $(`view-${v}`).classList.toggle("hidden", v !== name);
    $(`tab-${v}`).classList.toggle("active", v === name);
  }
  if (name === "model" && !MODEL.count) modelChanged();
  if (name === "measure") drawOverlay();
}

async function start() {
  $("tab-measure").addEventListener("click", () => showView("measure"));
  $("tab-model").addEventListener("click", () => showView("model"));
  $("tab-batch").addEventListener("click", () => showView("batch"));
  initMeasure();
  initModel();
  initBatch();
  try {
    await loadState();
    document.body.dataset.state = "ready";
    if (M.state.batch_dir) { $("batch-dir").value = M.state.batch_dir; openBatch(); }
    if (M.state.photos.length) showPhoto(M.state.photos[0].id);
    else if (M.state.batch_dir) showView("batch");
    else status("open a photo to measure");
  } catch (e) { status(e.message, true); }
}
start();
