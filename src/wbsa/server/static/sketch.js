// wbsa serve: the sketch of the view (camera and person from above and from the side), an SVG drawn from the
// answer's view. app.js calls showView; this file uses app.js's $, fmt and spread.
"use strict";

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
  const above = svg("text", { x: cx, y: 18, "text-anchor": "middle", "font-size": 12, fill: "#5b6577" });
  above.textContent = "from above";
  s.append(above);
  // from the side: the person upright, the camera at its elevation; the whole range −90° … 90° is drawn
  const px = 350, py = 150, R = 95, elev = v.elevation_used_deg * Math.PI / 180;
  const side = svg("text", { x: px + 20, y: 18, "text-anchor": "middle", "font-size": 12, fill: "#5b6577" });
  side.textContent = "from the side";
  s.append(side);
  s.append(svg("path", { d: `M${px},${py - R} A${R},${R} 0 0 1 ${px},${py + R}`, fill: "none", stroke: "#d7dce4" }));
  for (const t of [-90, -45, 0, 45, 90]) {
    const a = t * Math.PI / 180;
    const [tx, ty] = [px + R * Math.cos(a), py - R * Math.sin(a)];
    s.append(svg("line", { x1: tx, y1: ty, x2: px + (R + 6) * Math.cos(a), y2: py - (R + 6) * Math.sin(a), stroke: "#9aa3b2" }));
    const label = svg("text", { x: px + (R + 10) * Math.cos(a), y: py - (R + 10) * Math.sin(a) + 4, "font-size": 10, fill: "#9aa3b2" });
    label.textContent = `${t}°`;
    s.append(label);
  }
  s.append(svg("line", { x1: px, y1: py - 45, x2: px, y2: py + 45, stroke: "#8a5a3c", "stroke-width": 7, "stroke-linecap": "round" }));
  s.append(svg("circle", { cx: px, cy: py - 58, r: 9, fill: "#e5b08a", stroke: "#8a5a3c" }));
  const [camx, camy] = [px + R * Math.cos(elev), py - R * Math.sin(elev)];
  s.append(svg("line", { x1: px, y1: py, x2: camx, y2: camy, stroke: "#0b63c5", "stroke-dasharray": "4 4" }));
  const cam = svg("g", { id: "side-camera", transform: `translate(${camx},${camy}) rotate(${-v.elevation_used_deg})` });
  cam.append(svg("rect", { x: -8, y: -7, width: 16, height: 14, rx: 2, fill: "#0b63c5" }));
  s.append(cam);
  const et = svg("text", { x: px, y: 290, "text-anchor": "middle", "font-size": 12, fill: "#5b6577" });
  et.textContent = `elevation ${fmt(v.elevation_used_deg, 0)}° (+: camera above)`;
  s.append(et);
  $("view-line").textContent = `Azimuth ${fmt(v.azimuth_deg, 0)}°${spread(v.azimuth_sd_deg)} (0 = in front, 90 = at the person's left; its mirror image, −azimuth, looks the same${v.uncertain ? "; the faint camera: front and back may be swapped" : ""}), elevation ${fmt(v.elevation_deg, 0)}°${spread(v.elevation_sd_deg)}, ${fmt(v.distance_m, 2)} m away.`;
}

