// wbsa serve: the page's logic. Sends the form to the server, shows the answer; no library, no build step.
"use strict";

const $ = (id) => document.getElementById(id);
let current = null;       // the answer shown
let viewer = null;
let info = { max_upload_bytes: Infinity };

function el(tag, attrs, text) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs || {})) e.setAttribute(k, v);
  if (text !== undefined) e.textContent = text;
  return e;
}

function showError(message) {
  const box = $("error");
  box.textContent = message || "";
  box.hidden = !message;
}

function setBusy(on) {
  $("busy").hidden = !on;
  $("go").disabled = on;
  document.body.dataset.busy = on ? "1" : "0";
}

async function loadInfo() {
  info = await (await fetch("api/info")).json();
  for (const p of info.presets) $("camera").append(el("option", { value: p.name }, `${p.name} (${p.width} × ${p.height})`));
  for (const m of info.methods) $("method").append(el("option", { value: m }, m));
}

function formData(files) {
  const fd = new FormData();
  for (const f of files) fd.append("depth", f, f.name);
  fd.append("camera", $("camera").value);
  fd.append("clothing_cm", $("clothing").value);
  fd.append("method", $("method").value);
  fd.append("height_cm", $("height").value);
  fd.append("mass_kg", $("mass").value);
  fd.append("sex", $("sex").value);
  fd.append("azimuth_deg", $("azimuth").value);
  fd.append("elevation_deg", $("elevation").value);
  const cam = $("intrinsics").files[0];
  if (cam) fd.append("intrinsics", cam, cam.name);
  return fd;
}

async function readAnswer(response) {
  let body;
  try { body = await response.json(); } catch (e) { body = { error: `the server answered ${response.status} without a message` }; }
  return body;
}

async function send(files) {
  if (!files.length) { showError("choose or drop a depth file first"); return; }
  const bytes = files.reduce((n, f) => n + f.size, 0);
  if (bytes > info.max_upload_bytes) {
    showError(`the upload is ${(bytes / 2 ** 20).toFixed(1)} MiB, above this server's limit of ${(info.max_upload_bytes / 2 ** 20).toFixed(0)} MiB; send one depth image at a time, or a smaller image`);
    return;
  }
  if (files.length > 1) return sendBatch(files);
  showError("");
  setBusy(true);
  try {
    const response = await fetch("api/estimate", { method: "POST", body: formData(files) });
    show(await readAnswer(response));
  } catch (e) {
    showError(`the server did not answer (${e.message}); is wbsa serve still running?`);
  } finally {
    setBusy(false);
  }
}

async function pickAt(x, y) {
  if (!current || !current.id) return;
  showError("");
  setBusy(true);
  try {
    const response = await fetch(`api/result/${current.id}/pick?pick=${x},${y}`, { method: "POST" });
    show(await readAnswer(response));
  } catch (e) {
    showError(`the server did not answer (${e.message}); is wbsa serve still running?`);
  } finally {
    setBusy(false);
  }
}

function fmt(v, digits) { return Number(v).toFixed(digits); }
// " ± 3°" for a spread that was estimated, nothing for one that was not (a fitted body's view)
function spread(v) { return v === null || v === undefined ? "" : ` ± ${fmt(v, 0)}°`; }

function show(a) {
  $("batch").hidden = true;
  if (a.error) showError(a.error);
  if (!a.depth) { if (!a.error) showError("the server's answer holds no result"); return; }
  current = a;
  $("result").hidden = false;
  const ok = a.error === undefined;
  document.body.dataset.answer = ok ? a.id : "";
  $("wbsa-value").textContent = ok ? fmt(a.wbsa_m2, 2) : "—";
  $("wbsa-value").dataset.wbsaM2 = ok ? a.wbsa_m2 : "";
  $("interval").textContent = ok ? `${Math.round(100 * a.level)} % interval ${fmt(a.wbsa_lo_m2, 2)} – ${fmt(a.wbsa_hi_m2, 2)} m²` : "no estimate: see the message above";
  $("method-line").textContent = ok ? `Method: ${a.method_text}` : "";
  $("file-line").textContent = a.name ? `File: ${a.name}` : "";
  showDepth(a.depth);
  showFlags(ok ? a.flags : null);
  showView(ok ? a.view : null);
  showFormulae(ok ? a.formulae : null, ok ? a.wbsa_m2 : null);
  showDownloads(ok ? a.downloads : []);
  if (ok) showMeshes(a.meshes); else if (viewer) viewer.clear();
}

function showDepth(d) {
  const img = $("depth-img");
  img.src = d.url;
  img.dataset.width = d.width;
  img.dataset.height = d.height;
  $("depth-legend").textContent = `Colour by distance: blue ${fmt(d.near_m, 2)} m (near) to red ${fmt(d.far_m, 2)} m (far), grey: no return. White outline: the person measured.`;
}

function showFlags(flags) {
  const list = $("flag-list");
  list.replaceChildren();
  $("flags").hidden = !flags || flags.length === 0;
  $("no-flags").hidden = !flags || flags.length > 0;
  for (const f of flags || []) {
    const li = el("li", { "data-flag": f.name });
    li.append(el("b", {}, f.meaning.charAt(0).toUpperCase() + f.meaning.slice(1) + "."));
    li.append(el("span", { class: "todo" }, f.todo));
    li.append(el("span", { class: "detail" }, `${f.name}: ${f.detail}`));
    list.append(li);
  }
}

function svg(tag, attrs) {
  const e = document.createElementNS("http://www.w3.org/2000/svg", tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  return e;
}

// Top-down sketch: world +X to the right, the person's front (world -Y) down; the camera at its azimuth
// (0 = in front, 90 = at the person's left). Elevation in a side inset.
function showView(v) {
  const s = $("sketch");
  s.replaceChildren();
  if (!v) { $("view-line").textContent = ""; return; }
  const cx = 150, cy = 130, r = 95;
  const az = v.azimuth_used_deg * Math.PI / 180, sd = Math.min(v.azimuth_sd_deg, 90) * Math.PI / 180;
  const at = (a, rad) => [cx + rad * Math.sin(a), cy + rad * Math.cos(a)];
  const [a0x, a0y] = at(az - sd, r), [a1x, a1y] = at(az + sd, r);
  s.append(svg("path", { d: `M${cx},${cy} L${a0x},${a0y} A${r},${r} 0 0 0 ${a1x},${a1y} Z`, fill: "#cfe0f7", stroke: "none" }));
  const cams = [[az, 1]];
  if (v.uncertain) cams.push([Math.PI - az, 0.35]);  // front and back may be swapped
  for (const [a, opacity] of cams) {
    const [x, y] = at(a, r);
    const g = svg("g", { transform: `translate(${x},${y}) rotate(${-a * 180 / Math.PI})`, opacity: String(opacity) });
    g.append(svg("rect", { x: -14, y: -8, width: 28, height: 16, rx: 3, fill: "#0b63c5" }));
    g.append(svg("rect", { x: -5, y: -14, width: 10, height: 6, fill: "#0b63c5" }));
    s.append(g);
    s.append(svg("line", { x1: cx, y1: cy, x2: x, y2: y, stroke: "#0b63c5", "stroke-dasharray": "4 4", opacity: String(opacity) }));
  }
  s.append(svg("ellipse", { cx, cy, rx: 26, ry: 13, fill: "#f2c7a5", stroke: "#8a5a3c" }));
  s.append(svg("circle", { cx, cy: cy + 3, r: 8, fill: "#e5b08a", stroke: "#8a5a3c" }));
  s.append(svg("path", { d: `M${cx - 4},${cy + 12} L${cx},${cy + 19} L${cx + 4},${cy + 12} Z`, fill: "#8a5a3c" }));
  const front = svg("text", { x: cx, y: cy + 34, "text-anchor": "middle", "font-size": 11, fill: "#5b6577" });
  front.textContent = "front";
  s.append(front);
  // elevation inset
  const ex = 40, ey = 280, el_ = v.elevation_used_deg * Math.PI / 180;
  s.append(svg("line", { x1: ex, y1: ey, x2: ex, y2: ey - 40, stroke: "#8a5a3c", "stroke-width": 5 }));
  s.append(svg("line", { x1: ex, y1: ey - 20, x2: ex + 70 * Math.cos(el_), y2: ey - 20 - 70 * Math.sin(el_), stroke: "#0b63c5", "stroke-dasharray": "4 4" }));
  s.append(svg("rect", { x: ex + 70 * Math.cos(el_) - 6, y: ey - 20 - 70 * Math.sin(el_) - 5, width: 12, height: 10, fill: "#0b63c5" }));
  const et = svg("text", { x: ex + 90, y: ey - 5, "font-size": 11, fill: "#5b6577" });
  et.textContent = `elevation ${fmt(v.elevation_used_deg, 0)}°`;
  s.append(et);
  $("view-line").textContent = `Azimuth ${fmt(v.azimuth_deg, 0)}°${spread(v.azimuth_sd_deg)} (0 = in front, 90 = at the person's left; its mirror image, −azimuth, looks the same${v.uncertain ? "; the faint camera: front and back may be swapped" : ""}), elevation ${fmt(v.elevation_deg, 0)}°${spread(v.elevation_sd_deg)}, ${fmt(v.distance_m, 2)} m away.`;
}

function showFormulae(f, wbsa) {
  const box = $("formulae");
  box.hidden = !f;
  if (!f) return;
  $("formulae-error").hidden = !f.error;
  $("formulae-error").textContent = f.error || "";
  const body = $("formulae-table").querySelector("tbody");
  body.replaceChildren();
  const row = (name, value, cls) => {
    const tr = el("tr", cls ? { class: cls } : {});
    tr.append(el("td", {}, name), el("td", { class: "num" }, fmt(value, 3)));
    body.append(tr);
  };
  if (f.error) return;
  row("This depth image (wbsa)", wbsa, "own");
  for (const r of f.rows) row(r.name, r.bsa_m2);
}

function showDownloads(items) {
  const p = $("downloads");
  p.replaceChildren();
  for (const d of items) p.append(el("a", { href: d.url, download: d.filename }, d.label));
}

async function showMeshes(meshes) {
  if (!viewer) viewer = new WbsaViewer($("viewer"));
  try {
    const n = await viewer.show(meshes);
    $("viewer-line").textContent = `${meshes.map((m) => m.name).join(", ")}: ${n.toLocaleString()} triangles.`;
  } catch (e) {
    $("viewer-line").textContent = `the 3-D view could not be drawn (${e.message})`;
  }
}

// ------------------------------------------------------------------ batch
async function sendBatch(files) {
  showError("");
  $("result").hidden = true;
  setBusy(true);
  let progress;
  try {
    const response = await fetch("api/batch", { method: "POST", body: formData(files) });
    progress = await readAnswer(response);
    if (progress.error) { showError(progress.error); return; }
    $("batch").hidden = false;
    while (true) {
      showBatch(progress);
      if (progress.done) break;
      await new Promise((r) => setTimeout(r, 400));
      progress = await readAnswer(await fetch(`api/batch/${progress.id}`));
      if (progress.error) { showError(progress.error); break; }
    }
  } catch (e) {
    showError(`the server did not answer (${e.message}); is wbsa serve still running?`);
  } finally {
    setBusy(false);
  }
}

function showBatch(p) {
  $("batch-progress").max = p.total;
  $("batch-progress").value = p.done_count;
  $("batch-count").textContent = `${p.done_count} of ${p.total} done`;
  const csv = $("batch-csv");
  csv.hidden = !p.csv;
  if (p.csv) { csv.href = p.csv; csv.setAttribute("download", "wbsa-batch.csv"); }
  const body = $("batch-table").querySelector("tbody");
  body.replaceChildren();
  for (const r of p.rows) {
    const tr = el("tr");
    tr.append(el("td", {}, r.file));
    tr.append(el("td", { class: "num" }, r.error ? "" : fmt(r.wbsa_m2, 3)));
    tr.append(el("td", { class: "num" }, r.error ? "" : `${fmt(r.wbsa_lo_m2, 3)} – ${fmt(r.wbsa_hi_m2, 3)}`));
    tr.append(el("td", {}, (r.flags || []).join(", ")));
    tr.append(el("td", { class: "error-inline" }, r.error || ""));
    body.append(tr);
  }
}

// ------------------------------------------------------------------ wiring
function init() {
  loadInfo().catch((e) => showError(`the server did not answer (${e.message})`));
  $("form").addEventListener("submit", (e) => { e.preventDefault(); send([...$("depth-file").files]); });
  $("depth-file").addEventListener("change", () => send([...$("depth-file").files]));
  const drop = $("drop");
  drop.addEventListener("dragover", (e) => { e.preventDefault(); drop.classList.add("over"); });
  drop.addEventListener("dragleave", () => drop.classList.remove("over"));
  drop.addEventListener("drop", (e) => {
    e.preventDefault();
    drop.classList.remove("over");
    send([...e.dataTransfer.files]);
  });
  $("depth-img").addEventListener("click", (e) => {
    const img = e.currentTarget;
    const x = Math.floor(e.offsetX * Number(img.dataset.width) / img.clientWidth);
    const y = Math.floor(e.offsetY * Number(img.dataset.height) / img.clientHeight);
    pickAt(x, y);
  });
}

document.addEventListener("DOMContentLoaded", init);
