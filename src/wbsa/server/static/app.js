// wbsa serve: the page's logic. Sends the form to the server, shows the answer; no library, no build step.
"use strict";

const $ = (id) => document.getElementById(id);
let current = null;       // the answer shown
let viewer = null;
let info = { max_upload_bytes: Infinity };
let lastFiles = null;     // the depth file last measured alone, sent again when the camera changes
let waitingForClothes = null;  // a file chosen before the clothes: measured once they are chosen
let rerunWaiting = "";    // a camera chosen while busy: run again when the current estimate ends
window.progressLog = [];  // every progress line of the last estimate (the tests read it)

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
  $("go").disabled = on;
  document.body.dataset.busy = on ? "1" : "0";
}

async function loadInfo() {
  info = await (await fetch("api/info")).json();
  for (const p of info.presets) $("camera").append(el("option", { value: p.name }, `${p.name} (${p.width} × ${p.height})`));
  for (const m of info.methods) $("method").append(el("option", { value: m }, m));
  [$("height").min, $("height").max] = info.limits.height_cm;  // the library's table of limits
  for (const c of info.clothes) {
    const words = c.words.charAt(0).toUpperCase() + c.words.slice(1);
    $("clothes").append(el("option", { value: c.name }, `${words} (${fmt(c.layer_cm, 1)} ± ${fmt(c.sd_cm, 1)} cm)`));
  }
}

function formData(files) {
  const fd = new FormData();
  for (const f of files) fd.append("depth", f, f.name);
  fd.append("camera", $("camera").value);
  fd.append("clothes", $("clothes").value);
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

// The stages of an estimate as the server reports them (wbsa.server.progress), in the page's words.
const STAGES = {
  reading: "Reading the depth file",
  subject: "Finding and measuring the person",
  regression: "Regression: predicting the area from the measured surface",
  "body-fit": "Fitting a whole body to the picture",
  answer: "Making the answer and the downloads",
};

function startProgress() {
  window.progressLog = [];
  $("progress-stages").replaceChildren();
  $("progress-stage").textContent = "Sending the file";
  $("progress-count").textContent = "";
  $("progress-bar").removeAttribute("value");
  $("progress").hidden = false;
  $("progress").scrollIntoView({ block: "nearest" });  // a phone: the form fills the screen above it
}

function showProgress(p) {
  window.progressLog.push(p);
  const list = $("progress-stages");
  let item = list.querySelector(`li[data-stage="${p.stage}"]`);
  for (const li of list.children) if (li !== item) li.classList.add("done");
  if (!item) {
    item = el("li", { "data-stage": p.stage }, STAGES[p.stage] || p.stage);
    list.append(item);
  }
  $("progress-stage").textContent = STAGES[p.stage] || p.stage;
  const steps = p.total > 1;
  $("progress-count").textContent = steps ? `step ${p.done} of ${p.total}` : "";
  if (steps) { $("progress-bar").max = p.total; $("progress-bar").value = p.done; }
  else $("progress-bar").removeAttribute("value");
  if (steps) item.dataset.steps = `${p.done}/${p.total}`;
}

// One answer: JSON, or the progress stream (one JSON object a line, the answer last).
async function readAnswer(response) {
  const type = response.headers.get("content-type") || "";
  if (!type.startsWith("application/x-ndjson") || !response.body) {
    try { return await response.json(); } catch (e) { return { error: `the server answered ${response.status} without a message` }; }
  }
  const reader = response.body.getReader();
  const decoder = new TextDecoder();
  let buffered = "", last = null;
  const take = (line) => {
    if (!line.trim()) return;
    const msg = JSON.parse(line);
    if (msg.progress) showProgress(msg.progress);
    else if (msg.answer) last = msg.answer;
  };
  while (true) {
    const { value, done } = await reader.read();
    if (done) break;
    buffered += decoder.decode(value, { stream: true });
    let cut;
    while ((cut = buffered.indexOf("\n")) >= 0) { take(buffered.slice(0, cut)); buffered = buffered.slice(cut + 1); }
  }
  take(buffered);
  return last || { error: "the server stopped before its answer; send the file again" };
}

async function estimate(url, body) {
  showError("");
  setBusy(true);
  startProgress();
  try {
    const response = await fetch(url, { method: "POST", body, headers: { Accept: "application/x-ndjson" } });
    const answer = await readAnswer(response);
    show(answer);
    return answer;
  } catch (e) {
    showError(`the server did not answer (${e.message}); is wbsa serve still running?`);
    return null;
  } finally {
    $("progress").hidden = true;
    setBusy(false);
  }
}

// rerun: what changed, said on the answer ("" for a new file)
async function send(files, rerun = "") {
  if (!files.length) { showError("choose or drop a depth file first"); return; }
  const bytes = files.reduce((n, f) => n + f.size, 0);
  if (bytes > info.max_upload_bytes) {
    showError(`the upload is ${(bytes / 2 ** 20).toFixed(1)} MiB, above this server's limit of ${(info.max_upload_bytes / 2 ** 20).toFixed(0)} MiB; send one depth image at a time, or a smaller image`);
    return;
  }
  if (!$("clothes").value) {  // clothes are stated, never assumed
    waitingForClothes = files;
    $("clothes").classList.add("needed");
    $("clothes").focus();
    showError("Choose what the person wears (under “What the person wears”): the file is measured as soon as you do.");
    return;
  }
  waitingForClothes = null;
  $("clothes").classList.remove("needed");
  if (files.length > 1) { lastFiles = null; return sendBatch(files); }
  lastFiles = files;
  const body = formData(files);
  if (rerun && current && Array.isArray(current.pick)) body.append("pick", current.pick.join(","));  // the same person
  const answer = await estimate("api/estimate", body);
  const note = $("rerun-note");
  note.hidden = !(rerun && answer);
  note.textContent = rerun ? `Measured again with ${rerun}, chosen after the depth file.` : "";
  document.body.dataset.reruns = String(Number(document.body.dataset.reruns || 0) + (rerun && answer ? 1 : 0));
  if (rerunWaiting) { const why = rerunWaiting; rerunWaiting = ""; send(lastFiles, why); }
}

// The camera or the clothes changed after a depth file was measured: measure it again with them.
function choiceChanged(what) {
  if (!lastFiles) return;
  if (document.body.dataset.busy === "1") { rerunWaiting = what; return; }
  send(lastFiles, what);
}

async function pickAt(x, y) {
  if (!current || !current.id) return;
  await estimate(`api/result/${current.id}/pick?pick=${x},${y}`, null);
}

function fmt(v, digits) { return Number(v).toFixed(digits); }
// " ± 3°" for a spread that was estimated, nothing for one that was not (a fitted body's view)
function spread(v) { return v === null || v === undefined ? "" : ` ± ${fmt(v, 0)}°`; }

function interval(level, lo, hi) { return `${Math.round(100 * level)} % interval ${lo} – ${hi} m²`; }

function show(a) {
  $("batch").hidden = true;
  $("rerun-note").hidden = true;
  if (a.error) showError(a.error);
  if (!a.depth) {  // nothing was read: no earlier answer stays on show under the message
    if (!a.error) showError("the server's answer holds no result");
    $("result").hidden = true;
    document.body.dataset.answer = "";
    return;
  }
  current = a;
  $("result").hidden = false;
  const ok = a.error === undefined;
  document.body.dataset.answer = ok ? a.id : "";
  // no answer: no number, sketch, 3-D view or downloads; the depth picture alone, large when a click is asked for
  for (const id of ["answer", "sketch-card", "viewer-card", "downloads-card"]) $(id).hidden = !ok;
  const choose = !ok && Boolean(a.choose_person);
  $("pick-card").hidden = ok || !choose;
  $("depth-card").hidden = !ok && choose;
  $((ok || !choose) ? "depth-slot" : "pick-slot").append($("depth-img"));
  $("depth-img").classList.toggle("large", choose);
  // large: as wide as the page allows while the whole picture stays in the window below the message
  $("depth-img").style.width = choose ? `min(100%, calc((100vh - 190px) * ${a.depth.width / a.depth.height}), ${4 * a.depth.width}px)` : "";
  $("result").classList.toggle("choose", choose);
  $("wbsa-value").textContent = ok ? a.shown.wbsa_m2 : "";
  $("wbsa-value").dataset.wbsaM2 = ok ? a.wbsa_m2 : "";
  $("interval").textContent = ok ? interval(a.level, a.shown.wbsa_lo_m2, a.shown.wbsa_hi_m2) : "";
  $("method-line").textContent = ok ? `Method: ${a.method_text}` : "";
  $("file-line").textContent = a.name ? `File: ${a.name}` + (ok ? `, camera ${a.camera}` : "") : "";
  showDepth(a.depth);
  showRoutes(ok ? a.routes : null, ok ? a.level : null);
  showFlags(ok ? (a.routes ? a.image_flags : a.flags) : null, Boolean(ok && a.routes));
  showView(ok ? a.view : null);
  showFormulae(ok ? a.formulae : null, ok ? a.wbsa_m2 : null);
  showDownloads(ok ? a.downloads : []);
  if (ok) showMeshes(a.meshes); else if (viewer) viewer.clear();
  if (ok) $("answer").scrollIntoView({ block: "nearest" });  // below the form on a phone
  else if (a.error && !choose) $("error").scrollIntoView({ block: "nearest" });
  if (choose) {  // the message heads the picture, which fills the window below it
    showError("");
    $("pick-title").textContent = a.error;
    const img = $("depth-img");
    const scroll = () => $("pick-card").scrollIntoView({ block: "start" });
    if (img.complete && img.naturalWidth) scroll(); else img.addEventListener("load", scroll, { once: true });
  }
}

function showDepth(d) {
  const img = $("depth-img");
  img.src = d.url;
  img.dataset.width = d.width;
  img.dataset.height = d.height;
  const legend = `Colour by distance: blue ${fmt(d.near_m, 2)} m (near) to red ${fmt(d.far_m, 2)} m (far), grey: no return.`;
  $("depth-legend").textContent = `${legend} White outline: the person measured.`;
  $("pick-legend").textContent = legend;
}

function flagItem(f) {
  const li = el("li", { "data-flag": f.name, title: f.name });
  li.append(el("b", {}, f.meaning.charAt(0).toUpperCase() + f.meaning.slice(1) + "."));
  li.append(el("span", { class: "todo" }, f.todo));
  li.append(el("span", { class: "detail" }, `Detail: ${f.detail}`));
  return li;
}

// With method both: the flags of the picture itself here, each route's own under its number.
function showFlags(flags, both) {
  const list = $("flag-list");
  list.replaceChildren();
  $("flags").hidden = !flags || flags.length === 0;
  $("no-flags").hidden = !flags || flags.length > 0;
  $("no-flags").textContent = both ? "All checks of the picture passed." : "All checks passed.";
  $("flags-title").textContent = both ? "Check the picture before you use the numbers" : "Check before you use the number";
  for (const f of flags || []) list.append(flagItem(f));
}

// Method both: each route with its own number, interval and flags, which one leads and why.
function showRoutes(r, level) {
  $("routes").hidden = !r;
  $("lead-label").hidden = !r;
  const list = $("route-list");
  list.replaceChildren();
  if (!r) return;
  $("lead-label").textContent = `${r.lead_label} (leads)`;
  $("lead-why").textContent = r.why;
  const rows = r.combined ? [r.combined, ...r.rows] : r.rows;
  for (const row of rows) {
    const box = el("div", { class: "route" + (row.leads ? " leads" : ""), "data-route": row.name });
    box.append(el("h3", {}, row.label + (row.leads ? " — leads" : "")));
    if (row.failed) {
      box.append(el("p", { class: "error-inline" }, `No answer: ${row.failed}`));
    } else {
      box.append(el("div", { class: "route-value" }, `${fmt(row.wbsa_m2, 2)} m²`));
      box.append(el("div", { class: "small" }, interval(level, fmt(row.wbsa_lo_m2, 2), fmt(row.wbsa_hi_m2, 2))));
      const flags = row.flags || [];
      if (flags.length) {
        const ul = el("ul", { class: "route-flags" });
        for (const f of flags) ul.append(flagItem(f));
        box.append(ul);
      } else if (row.flags) box.append(el("p", { class: "ok small" }, "No warnings for this method."));
    }
    list.append(box);
  }
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
  const legend = $("viewer-legend");
  legend.replaceChildren();
  try {
    const n = await viewer.show(meshes);
    meshes.forEach((m, k) => {
      const [r, g, b] = WbsaViewer.COLOURS[k % WbsaViewer.COLOURS.length];
      const li = el("li", { "data-mesh": m.name });
      const swatch = el("span", { class: "swatch" });
      swatch.style.background = `rgb(${r},${g},${b})`;  // CSSOM, allowed by the page's CSP (no inline style)
      li.append(swatch, document.createTextNode(m.label || m.name));
      legend.append(li);
    });
    $("viewer-line").textContent = `${n.toLocaleString()} triangles.`;
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
  $("intrinsics").addEventListener("change", () => {
    const f = $("intrinsics").files[0];
    choiceChanged(f ? `the camera file ${f.name}` : "the camera chosen");
  });
  $("clothes").addEventListener("change", () => {
    if (waitingForClothes) { const files = waitingForClothes; waitingForClothes = null; send(files); return; }
    choiceChanged(`the clothes: ${$("clothes").selectedOptions[0].textContent}`);
  });
  $("camera").addEventListener("change", () => choiceChanged(`the camera ${$("camera").selectedOptions[0].textContent}`));
  $("depth-img").addEventListener("click", (e) => {
    const img = e.currentTarget;
    const x = Math.floor(e.offsetX * Number(img.dataset.width) / img.clientWidth);
    const y = Math.floor(e.offsetY * Number(img.dataset.height) / img.clientHeight);
    pickAt(x, y);
  });
}

document.addEventListener("DOMContentLoaded", init);
