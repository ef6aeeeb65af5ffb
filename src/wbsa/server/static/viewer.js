// A small 3-D viewer for triangle meshes on a 2-D canvas (no WebGL needed, so it also draws in a browser
// without a GPU): flat shading, painter's order, drag to turn, wheel to zoom.
// Meshes: [{name, url}] (a binary PLY file, as wbsa writes them) or [{name, vertices: [x, y, z, ...], faces: [a, b, c, ...]}],
// in the camera frame (x right, y down, z forward, metres) unless frame: "world" (+z up).
"use strict";

const PLY_TYPES = {
  char: ["getInt8", 1], int8: ["getInt8", 1], uchar: ["getUint8", 1], uint8: ["getUint8", 1],
  short: ["getInt16", 2], int16: ["getInt16", 2], ushort: ["getUint16", 2], uint16: ["getUint16", 2],
  int: ["getInt32", 4], int32: ["getInt32", 4], uint: ["getUint32", 4], uint32: ["getUint32", 4],
  float: ["getFloat32", 4], float32: ["getFloat32", 4], double: ["getFloat64", 8], float64: ["getFloat64", 8],
};

function parsePly(buffer) {
  const bytes = new Uint8Array(buffer);
  const marker = "end_header";
  let end = -1;
  const head = new TextDecoder("ascii").decode(bytes.subarray(0, Math.min(bytes.length, 4096)));
  const at = head.indexOf(marker);
  if (!head.startsWith("ply") || at < 0) throw new Error("not a PLY file");
  end = at + marker.length;
  while (bytes[end] === 13 || bytes[end] === 10) { end++; if (bytes[end - 1] === 10) break; }
  const lines = head.slice(0, at).split(/\r?\n/);
  const format = lines.find((l) => l.startsWith("format")).split(/\s+/)[1];
  const elements = [];
  for (const l of lines) {
    const w = l.trim().split(/\s+/);
    if (w[0] === "element") elements.push({ name: w[1], count: Number(w[2]), props: [] });
    else if (w[0] === "property") {
      const e = elements[elements.length - 1];
      if (w[1] === "list") e.props.push({ list: true, countType: w[2], type: w[3], name: w[4] });
      else e.props.push({ type: w[1], name: w[2] });
    }
  }
  const out = { vertices: null, faces: null };
  if (format === "ascii") throw new Error("an ASCII PLY; wbsa writes binary PLY files");
  const little = format === "binary_little_endian";
  const view = new DataView(buffer);
  let off = end;
  const read = (type) => {
    const [fn, size] = PLY_TYPES[type];
    const v = view[fn](off, little); off += size; return v;
  };
  for (const e of elements) {
    const verts = e.name === "vertex" ? new Float32Array(3 * e.count) : null;
    const faces = e.name === "face" ? [] : null;
    for (let n = 0; n < e.count; n++) {
      for (const p of e.props) {
        if (p.list) {
          const k = read(p.countType);
          const idx = [];
          for (let t = 0; t < k; t++) idx.push(read(p.type));
          if (faces) for (let t = 1; t + 1 < k; t++) faces.push(idx[0], idx[t], idx[t + 1]);
        } else {
          const v = read(p.type);
          if (verts && (p.name === "x" || p.name === "y" || p.name === "z")) verts[3 * n + "xyz".indexOf(p.name)] = v;
        }
      }
    }
    if (verts) out.vertices = verts;
    if (faces) out.faces = Uint32Array.from(faces);
  }
  return out;
}

class WbsaViewer {
  constructor(canvas) {
    this.canvas = canvas;
    this.ctx = canvas.getContext("2d");
    this.meshes = [];
    this.yaw = 0; this.pitch = 0; this.zoom = 1;
    let drag = null;
    canvas.addEventListener("pointerdown", (e) => { drag = [e.clientX, e.clientY]; canvas.setPointerCapture(e.pointerId); });
    canvas.addEventListener("pointerup", () => { drag = null; });
    canvas.addEventListener("pointermove", (e) => {
      if (!drag) return;
      this.yaw += (e.clientX - drag[0]) * 0.01;
      this.pitch = Math.max(-1.5, Math.min(1.5, this.pitch + (e.clientY - drag[1]) * 0.01));
      drag = [e.clientX, e.clientY];
      this.requestDraw();
    });
    canvas.addEventListener("wheel", (e) => {
      e.preventDefault();
      this.zoom = Math.max(0.3, Math.min(5, this.zoom * Math.exp(-e.deltaY * 0.001)));
      this.requestDraw();
    }, { passive: false });
  }

  clear() {
    this.meshes = [];
    this.canvas.dataset.triangles = "0";
    this.ctx.clearRect(0, 0, this.canvas.width, this.canvas.height);
  }

  // Load and show meshes; resolves to the number of triangles drawn.
  async show(meshes) {
    const loaded = [];
    for (const m of meshes) {
      let data = m;
      if (m.url) {
        const response = await fetch(m.url);
        if (!response.ok) throw new Error(`${m.name}: the server answered ${response.status}`);
        data = parsePly(await response.arrayBuffer());
      }
      const v = Float32Array.from(data.vertices);
      if ((m.frame || "camera") === "camera") for (let i = 0; i < v.length; i += 3) { v[i + 1] = -v[i + 1]; v[i + 2] = -v[i + 2]; }
      else for (let i = 0; i < v.length; i += 3) { const y = v[i + 1]; v[i + 1] = v[i + 2]; v[i + 2] = -y; }
      loaded.push({ name: m.name, vertices: v, faces: Uint32Array.from(data.faces) });
    }
    this.meshes = loaded;
    let lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    for (const m of loaded) for (let i = 0; i < m.vertices.length; i++) {
      lo[i % 3] = Math.min(lo[i % 3], m.vertices[i]); hi[i % 3] = Math.max(hi[i % 3], m.vertices[i]);
    }
    this.center = lo.map((l, k) => (l + hi[k]) / 2);
    this.size = Math.max(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) || 1;
    this.yaw = 0; this.pitch = 0; this.zoom = 1;
    this.draw();
    return loaded.reduce((n, m) => n + m.faces.length / 3, 0);
  }

  requestDraw() {
    if (this.pending) return;
    this.pending = true;
    requestAnimationFrame(() => { this.pending = false; this.draw(); });
  }

  draw() {
    const { ctx, canvas } = this;
    const W = canvas.width, H = canvas.height;
    ctx.clearRect(0, 0, W, H);
    const cy = Math.cos(this.yaw), sy = Math.sin(this.yaw), cp = Math.cos(this.pitch), sp = Math.sin(this.pitch);
    const scale = 0.85 * Math.min(W, H) / this.size * this.zoom;
    const light = [0.3, 0.5, 0.8];
    const ln = Math.hypot(...light);
    const tris = [];
    const colours = WbsaViewer.COLOURS;
    let drawn = 0;
    this.meshes.forEach((m, k) => {
      const v = m.vertices, n = v.length / 3;
      const p = new Float32Array(3 * n);
      for (let i = 0; i < n; i++) {
        const x = v[3 * i] - this.center[0], y = v[3 * i + 1] - this.center[1], z = v[3 * i + 2] - this.center[2];
        const x1 = cy * x + sy * z, z1 = -sy * x + cy * z;  // turn about the vertical axis
        const y2 = cp * y - sp * z1, z2 = sp * y + cp * z1;  // then tilt
        p[3 * i] = W / 2 + scale * x1; p[3 * i + 1] = H / 2 - scale * y2; p[3 * i + 2] = z2;
      }
      const f = m.faces;
      for (let t = 0; t < f.length; t += 3) {
        const a = 3 * f[t], b = 3 * f[t + 1], c = 3 * f[t + 2];
        const ux = p[b] - p[a], uy = p[b + 1] - p[a + 1], uz = p[b + 2] - p[a + 2];
        const vx = p[c] - p[a], vy = p[c + 1] - p[a + 1], vz = p[c + 2] - p[a + 2];
        let nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
        const nn = Math.hypot(nx, ny, nz) || 1;
        const shade = Math.abs(nx * light[0] - ny * light[1] + nz * light[2]) / nn / ln;
        tris.push([p[a + 2] + p[b + 2] + p[c + 2], a, b, c, 0.25 + 0.75 * shade, k, p]);
      }
      drawn += f.length / 3;
    });
    tris.sort((s, t) => s[0] - t[0]);
    for (const [, a, b, c, shade, k, p] of tris) {
      const col = colours[k % colours.length];
      ctx.fillStyle = `rgb(${col[0] * shade | 0},${col[1] * shade | 0},${col[2] * shade | 0})`;
      ctx.beginPath();
      ctx.moveTo(p[a], p[a + 1]); ctx.lineTo(p[b], p[b + 1]); ctx.lineTo(p[c], p[c + 1]);
      ctx.closePath();
      ctx.fill();
    }
    canvas.dataset.triangles = String(drawn);
  }
}

// Each mesh's colour, in the order given (the page's legend reads them).
WbsaViewer.COLOURS = [[214, 160, 120], [120, 160, 214], [140, 190, 120]];

window.WbsaViewer = WbsaViewer;
window.parsePly = parsePly;
