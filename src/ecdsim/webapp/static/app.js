// ecdsim explorer: edits a config (JSON with unit strings), asks /api/deploy, plots with plotly.js.
"use strict";

const CONTROLS = [
  { path: ["gearbox", "ratio"], label: "gear ratio N" },
  { path: ["damper", "damping_rate"], label: "damper damping rate BD" },
  { path: ["damper", "coulomb_friction"], label: "damper friction FD" },
  { path: ["damper", "lubrication_friction", "at_0C"], label: "lubrication friction FL at 0 degC" },
  { path: ["gearbox", "coulomb_friction"], label: "gearbox friction FG" },
  { path: ["load", "system_friction", "at_0C"], label: "system friction FS at 0 degC" },
  { path: ["load", "start_torque"], label: "spring torque at start" },
  { path: ["load", "end_torque"], label: "spring torque at end" },
  { path: ["load", "travel"], label: "travel" },
  { path: ["load", "inertia"], label: "load inertia (dynamic method)" },
];
const STEPS = 1000;
const COLORS = ["#1f77b4", "#2ca02c", "#d62728", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2"];
const DASH = { exact: "solid", paper: "dash", dynamic: "dot" };

const state = { config: null, response: null, requests: 0, inFlight: false, pending: false };
window.ecdsim = state;

function getPath(obj, path) {
  let node = obj;
  for (const part of path) {
    if (node === null || typeof node !== "object" || !(part in node)) return undefined;
    node = node[part];
  }
  return node;
}

function setPath(obj, path, value) {
  let node = obj;
  for (const part of path.slice(0, -1)) node = node[part];
  node[path[path.length - 1]] = value;
}

// "1.3e-4 N*m*s/rad" -> {number: 1.3e-4, unit: "N*m*s/rad"}; a bare number has unit null.
function splitQuantity(value) {
  if (typeof value === "number") return { number: value, unit: null };
  if (typeof value !== "string") return null;
  const m = value.trim().match(/^([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*)$/);
  if (!m) return null;
  return { number: parseFloat(m[1]), unit: m[2] };
}

function joinQuantity(number, unit) {
  const text = Number(number.toPrecision(6)).toString();
  return unit === null ? Number(text) : `${text} ${unit}`;
}

function buildControls() {
  const box = document.getElementById("sliders");
  box.innerHTML = "";
  let hasInertia = false;
  for (const c of CONTROLS) {
    const q = splitQuantity(getPath(state.config, c.path));
    if (q === null) continue;
    if (c.path.join(".") === "load.inertia") hasInertia = true;
    const id = c.path.join(".");
    const span = Math.abs(q.number) || 1;
    const lo = q.number - 0.95 * span;
    const hi = q.number + 2 * span;
    const div = document.createElement("div");
    div.className = "control";
    div.innerHTML =
      `<label for="slider-${id}">${c.label} <span class="unit">[${q.unit === null ? "-" : q.unit}]</span></label>` +
      `<input type="range" id="slider-${id}" data-path="${id}" min="0" max="${STEPS}" step="1">` +
      ` <input type="text" id="field-${id}" data-path="${id}">`;
    box.appendChild(div);
    const slider = div.querySelector("input[type=range]");
    const field = div.querySelector("input[type=text]");
    const toValue = (s) => lo + ((hi - lo) * s) / STEPS;
    slider.value = String(Math.round(((q.number - lo) / (hi - lo)) * STEPS));
    field.value = Number(q.number.toPrecision(6)).toString();
    slider.addEventListener("input", () => {
      const v = toValue(Number(slider.value));
      field.value = Number(v.toPrecision(6)).toString();
      setPath(state.config, c.path, joinQuantity(v, q.unit));
      requestDeploy();
    });
    field.addEventListener("change", () => {
      const v = Number(field.value);
      if (!Number.isFinite(v)) { showErrors([`${id}: '${field.value}' is not a number`]); return; }
      setPath(state.config, c.path, joinQuantity(v, q.unit));
      requestDeploy();
    });
  }
  document.getElementById("inertia-note").textContent = hasInertia
    ? "The inertia acts in the dynamic method only; the quasi-static methods ignore it."
    : "No inertia slider: this config has no [load] inertia (the quasi-static methods do not use it; add it and method \"dynamic\" in the config for the dynamic method).";
  const temps = getPath(state.config, ["analysis", "temperatures"]) || ["25 degC"];
  document.getElementById("temperatures").value = temps
    .map((t) => { const q = splitQuantity(t); return q ? q.number : t; }).join(", ");
}

function showErrors(errors) {
  document.getElementById("errors").textContent = errors.length ? "error: " + errors.join("\nerror: ") : "";
}

async function postJson(url, body) {
  const r = await fetch(url, { method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify(body) });
  return r;
}

async function requestDeploy() {
  if (state.inFlight) { state.pending = true; return; }
  state.inFlight = true;
  state.pending = false;
  const sent = JSON.parse(JSON.stringify(state.config));
  try {
    const r = await postJson("/api/deploy", { config: sent });
    const body = await r.json();
    if (r.ok) { state.response = body; state.sentConfig = sent; showErrors([]); render(body); }
    else showErrors(body.errors || [`HTTP ${r.status}`]);
  } catch (e) {
    showErrors([String(e)]);
  } finally {
    state.inFlight = false;
    state.requests += 1;
    document.body.dataset.requests = String(state.requests);
    if (state.pending) requestDeploy();
  }
}

function fmt(v) { return v === null || v === undefined ? "stall" : Number(v).toPrecision(6); }

function render(body) {
  const doc = body.prediction;
  const time = body.trajectories.time_s;
  const traces = [];
  doc.methods.forEach((m) => {
    doc.cases.forEach((c, j) => {
      traces.push({
        x: time, y: body.trajectories.methods[m].angle_rad[j].map((a) => (a === null ? null : (a * 180) / Math.PI)),
        name: `${c.temperature_C} degC, ${m}`, mode: "lines",
        line: { color: COLORS[j % COLORS.length], dash: DASH[m] || "dashdot" },
      });
    });
  });
  Plotly.react("angle-plot", traces, {
    title: "deployed angle against time", margin: { t: 40 },
    xaxis: { title: "time since release [s]" }, yaxis: { title: "angle [deg]" },
  });
  const sweep = body.sweep;
  const sweepTraces = doc.methods.map((m) => ({
    x: sweep.temperature_C, y: sweep.methods[m].deployment_time_s, name: m, mode: "lines+markers",
    line: { dash: DASH[m] || "dashdot" },
  }));
  Plotly.react("sweep-plot", sweepTraces, {
    title: "deployment time against temperature", margin: { t: 40 },
    xaxis: { title: "temperature [degC]" }, yaxis: { title: "deployment time [s]" },
  });
  const head = document.querySelector("#results thead");
  const rows = document.querySelector("#results tbody");
  head.innerHTML = "<tr><th>T [degC]</th>" + doc.methods.map((m) => `<th>${m}: t [s]</th><th>${m}: end speed [rad/s]</th>`).join("") + "<th>BECD [N*m*s/rad]</th><th>FECD [N*m]</th></tr>";
  rows.innerHTML = doc.cases.map((c, i) =>
    `<tr><td class="num">${c.temperature_C}</td>` +
    doc.methods.map((m) =>
      `<td class="num" data-case="${i}" data-key="${m}.deployment_time_s">${fmt(c[m].deployment_time_s)}</td>` +
      `<td class="num" data-case="${i}" data-key="${m}.end_speed_rad_s">${fmt(c[m].end_speed_rad_s)}</td>`).join("") +
    `<td class="num" data-case="${i}" data-key="damping_rate_Nms_per_rad">${fmt(c.damping_rate_Nms_per_rad)}</td>` +
    `<td class="num" data-case="${i}" data-key="friction_Nm">${fmt(c.friction_Nm)}</td></tr>`).join("");
  document.getElementById("warnings").innerHTML = "";
  for (const w of doc.warnings) {
    const div = document.createElement("div");
    div.textContent = (w.method ? `[${w.method}] ` : "") + w.message;
    document.getElementById("warnings").appendChild(div);
  }
  document.getElementById("timing").textContent = `last computation ${body.compute_ms.toFixed(1)} ms on the server.`;
}

async function loadExample(which) {
  const r = await fetch(`/api/example?which=${which}`);
  const body = await r.json();
  useConfig(body.config, body.source);
}

function useConfig(config, source) {
  state.config = config;
  document.getElementById("source").textContent = source;
  buildControls();
  requestDeploy();
}

async function download(url, filename) {
  const r = await postJson(url, { config: state.config });
  if (!r.ok) { const body = await r.json(); showErrors(body.errors || [`HTTP ${r.status}`]); return; }
  const blob = await r.blob();
  const a = document.createElement("a");
  a.href = URL.createObjectURL(blob);
  a.download = filename;
  document.body.appendChild(a);
  a.click();
  a.remove();
}

document.getElementById("temperatures").addEventListener("change", (e) => {
  const items = e.target.value.split(",").map((s) => s.trim()).filter((s) => s.length);
  if (!state.config.analysis) state.config.analysis = {};
  state.config.analysis.temperatures = items.map((s) => (/[a-zA-Z]/.test(s) ? s : `${s} degC`));
  requestDeploy();
});
document.getElementById("load-example").addEventListener("click", () => loadExample("paper"));
document.getElementById("load-start").addEventListener("click", () => loadExample("start"));
document.getElementById("download-toml").addEventListener("click", () => download("/api/config.toml", "ecdsim-config.toml"));
document.getElementById("download-report").addEventListener("click", () => download("/api/report", "ecdsim-report.html"));
document.getElementById("upload").addEventListener("change", async (e) => {
  const file = e.target.files[0];
  if (!file) return;
  const r = await postJson("/api/config/parse", { toml: await file.text() });
  const body = await r.json();
  if (r.ok) useConfig(body.config, file.name); else showErrors(body.errors || [`HTTP ${r.status}`]);
});

loadExample("start");
