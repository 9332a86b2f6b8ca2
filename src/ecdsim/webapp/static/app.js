// ecdsim explorer: edits a config (JSON with unit strings), asks /api/deploy, plots with plotly.js.
//
// Units: the config's quantities keep their unit strings (what the user wrote) in both
// directions; a field shows the number of its own quantity with that unit, and a bare
// number typed into it gets that same unit back. Results arrive in SI (keys say their
// unit); they are shown in the display system (the server's `display_units` and `units`
// table: shown = SI * scale + offset), converted, never relabelled.
"use strict";

// Each control: its config path, its label and the kind of quantity it holds (the page
// shows it in the display system's unit of that kind; angles in degrees, as the plots).
const CONTROLS = [
  { path: ["gearbox", "ratio"], label: "gear ratio N", kind: "number" },
  { path: ["damper", "damping_rate"], label: "damper damping rate BD", kind: "damping_rate" },
  { path: ["damper", "coulomb_friction"], label: "damper friction FD", kind: "torque" },
  { path: ["damper", "lubrication_friction", "at_0C"], label: "lubrication friction FL at 0 degC", kind: "torque" },
  { path: ["gearbox", "coulomb_friction"], label: "gearbox friction FG", kind: "torque" },
  { path: ["load", "system_friction", "at_0C"], label: "system friction FS at 0 degC", kind: "torque" },
  { path: ["load", "start_torque"], label: "spring torque at start", kind: "torque", load: true },
  { path: ["load", "end_torque"], label: "spring torque at end", kind: "torque", load: true },
  { path: ["load", "travel"], label: "travel", kind: "angle", load: true },
  { path: ["load", "inertia"], label: "load inertia (dynamic method)", kind: "inertia" },
];
const STEPS = 1000;
const DIGITS = 6; // significant digits of every number shown
// One colour per temperature on every plot of the page, by its value over the page's
// temperatures: cold blue, dark green, hot red (the CLI's plots use the same three,
// ecdsim/plotting.py), each readable as a thin line on white.
const TEMPERATURE_ANCHORS = [[0x21, 0x66, 0xac], [0x1b, 0x78, 0x37], [0xb2, 0x18, 0x2b]];
const DASH = { exact: "solid", paper: "dash", dynamic: "dot" };
// Methods where a plot's lines are methods (deployment time against temperature): no
// temperature's hue, so that blue always means cold.
const METHOD_COLORS = { paper: "#6b6b6b", exact: "#111111", dynamic: "#6a3d9a" };
const NARROW = 700; // px: below this the page is a phone's (legends and toolbars adapt)
const METHOD_NOTES = {
  paper: "paper: the paper's Eq. 8-11, quasi-static, with the arithmetic mean of the start and end speeds (no inertia).",
  exact: "exact: the exact solution of the same quasi-static equations (speed set by the torque balance at each angle; no inertia).",
  dynamic: "dynamic: integrates the equation of motion in time with the load and reflected rotor inertia, stick-slip friction and the end stop (docs/dynamics.md); it needs [load] inertia and is the only method that uses it.",
};
// SI display table, used until the server sends its own (`units` in its answers).
const SI_UNITS = {
  temperature: { unit: "degC", scale: 1, offset: 0 },
  torque: { unit: "N*m", scale: 1, offset: 0 },
  damping_rate: { unit: "N*m*s/rad", scale: 1, offset: 0 },
  angular_speed: { unit: "rad/s", scale: 1, offset: 0 },
  time: { unit: "s", scale: 1, offset: 0 },
  energy: { unit: "J", scale: 1, offset: 0 },
  length: { unit: "m", scale: 1, offset: 0 },
  per_kelvin: { unit: "1/K", scale: 1, offset: 0 },
  torque_per_kelvin: { unit: "N*m/K", scale: 1, offset: 0 },
};

const state = {
  config: null, response: null, sentConfig: null, requests: 0, inFlight: false, pending: false,
  units: SI_UNITS, displayUnits: "si", choice: "config", pinned: null, stale: false, fit: null, fits: 0,
  wing: null, // the answer of POST /api/wing when the config is a wing file (wing.js)
};
window.ecdsim = state;

// ---------------------------------------------------------------- numbers and units

// A number to DIGITS significant digits without float noise: -39.99999999999997 -> "-40".
function sig(v, digits = DIGITS) {
  if (v === null || v === undefined || !Number.isFinite(Number(v))) return "-";
  const text = String(Number(Number(v).toPrecision(digits)));
  return text === "-0" ? "0" : text;
}

function unitOf(kind) {
  const u = (state.units && state.units[kind]) || SI_UNITS[kind] || { unit: "", scale: 1, offset: 0 };
  return u;
}
function show(kind, si) { // SI value -> display number (null stays null)
  if (si === null || si === undefined) return null;
  const u = unitOf(kind);
  return si * u.scale + u.offset;
}
function label(kind) { return unitOf(kind).unit; }
function showDiff(kind, si) { // a difference: scale only, no offset
  if (si === null || si === undefined) return null;
  return si * unitOf(kind).scale;
}

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
  for (const part of path.slice(0, -1)) {
    if (node[part] === null || typeof node[part] !== "object") node[part] = {};
    node = node[part];
  }
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
  const text = sig(number);
  return unit === null ? Number(text) : `${text} ${unit}`;
}

function escapeHtml(text) {
  return String(text).replace(/[&<>"']/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;", "'": "&#39;" })[c]);
}

// ---------------------------------------------------------------- units typed in fields

// SI value of each unit symbol a quantity may be written in (exact definitions, as
// ecdsim/units_display.py). The server parses every field (pint); the page needs these
// only to show a config's value in the display system.
const LBM = 0.45359237, LBF = LBM * 9.80665, INCH = 0.0254;
const UNIT_FACTORS = {
  N: 1, mN: 1e-3, kN: 1e3, lbf: LBF, ozf: LBF / 16, kgf: 9.80665, gf: 9.80665e-3,
  m: 1, mm: 1e-3, cm: 1e-2, km: 1e3, in: INCH, inch: INCH, ft: 12 * INCH,
  s: 1, ms: 1e-3, min: 60, h: 3600, rad: 1, mrad: 1e-3, deg: Math.PI / 180, degree: Math.PI / 180,
  kg: 1, g: 1e-3, lbm: LBM, lb: LBM, oz: LBM / 16, J: 1, kJ: 1e3, W: 1, K: 1,
};

// "N*m*s/rad" -> its SI factor; null for what the page does not know (the server does).
function unitFactor(text) {
  if (text === null || text === undefined) return null;
  const unit = text.replace(/\s+/g, "").replace(/\*\*/g, "^").replace(/·/g, "*");
  if (unit === "") return 1;
  let factor = 1;
  let sign = 1;
  for (const token of unit.split(/(?=[*/])/)) {
    const op = token[0] === "*" || token[0] === "/" ? token[0] : "*";
    const body = token[0] === "*" || token[0] === "/" ? token.slice(1) : token;
    const m = body.match(/^(?:([A-Za-z]+)(?:\^([-+]?\d+))?|1)$/);
    if (!m) return null;
    sign = op === "/" ? -1 : 1;
    if (m[1] === undefined) continue; // "1/K"
    const base = UNIT_FACTORS[m[1]];
    if (base === undefined) return null;
    factor *= base ** (sign * Number(m[2] || 1));
  }
  return factor;
}

// A temperature in degC from a number and its unit (degC, degF, K); null if unknown.
function toCelsius(number, unit) {
  const u = (unit || "degC").replace(/\s+/g, "");
  if (u === "degC" || u === "°C" || u === "C") return number;
  if (u === "degF" || u === "°F" || u === "F") return (number - 32) * 5 / 9;
  if (u === "K" || u === "kelvin") return number - 273.15;
  return null;
}

// The display unit of a control's kind: {unit, scale, offset} with shown = SI * scale +
// offset. Angles are shown in degrees on every page (as the plots and stall angles).
function displayUnit(kind) {
  if (kind === "angle") return { unit: "deg", scale: 180 / Math.PI, offset: 0 };
  if (kind === "number") return { unit: "", scale: 1, offset: 0 };
  return unitOf(kind);
}

// ---------------------------------------------------------------- controls

// Each control shows its quantity in the display system (SI or US customary: the same
// system as the results), whatever unit the config wrote it in; a bare number typed in
// a field is in that unit, and a number with a unit ("33 lbf*in") is sent as typed.
function buildControls() {
  const box = document.getElementById("sliders");
  box.innerHTML = "";
  let hasInertia = false;
  state.builtFor = state.displayUnits;
  for (const c of CONTROLS) {
    const q = splitQuantity(getPath(state.config, c.path));
    if (q === null) continue;
    if (c.path.join(".") === "load.inertia") hasInertia = true;
    const id = c.path.join(".");
    // The value in the display unit, or (a unit the page cannot convert) in its own.
    const factor = c.kind === "number" ? 1 : unitFactor(q.unit);
    const shown = factor === null ? null : displayUnit(c.kind);
    const unitText = shown === null ? (q.unit || "-") : (shown.unit || "-");
    const sendUnit = shown === null ? q.unit : (shown.unit || null);
    const value = shown === null ? q.number : q.number * factor * shown.scale + shown.offset;
    const span = Math.abs(value) || 1;
    const lo = value - 0.95 * span;
    const hi = value + 2 * span;
    const div = document.createElement("div");
    div.className = "control";
    // 0 degC is 32 degF: the friction laws' at_0C values named in the page's unit.
    const name = unitOf("temperature").unit === "degF" ? c.label.replace("at 0 degC", "at 32 degF") : c.label;
    div.innerHTML =
      `<label for="slider-${id}">${escapeHtml(name)} <span class="unit">[${escapeHtml(unitText)}]</span></label>` +
      `<input type="range" id="slider-${id}" data-path="${id}" min="0" max="${STEPS}" step="1">` +
      ` <input type="text" id="field-${id}" data-path="${id}" inputmode="text">`;
    box.appendChild(div);
    const slider = div.querySelector("input[type=range]");
    const field = div.querySelector("input[type=text]");
    field.setAttribute("aria-label", `${name} value [${unitText}] (a number, or a number with a unit)`);
    const toValue = (position) => lo + ((hi - lo) * position) / STEPS;
    const toPosition = (v) => String(Math.round(((v - lo) / (hi - lo)) * STEPS));
    const setText = (v) => {
      slider.setAttribute("aria-valuetext", `${sig(v)} ${unitText}`);
      field.value = sig(v);
    };
    slider.value = toPosition(value);
    setText(value);
    const edited = () => { if (c.load) delete (state.config.load || {}).placeholder; };
    slider.addEventListener("input", () => {
      const v = toValue(Number(slider.value));
      setText(v);
      setPath(state.config, c.path, joinQuantity(v, sendUnit));
      edited();
      requestDeploy();
    });
    field.addEventListener("change", () => {
      const text = field.value.trim();
      const typed = splitQuantity(text);
      if (text === "" || typed === null || (typed.unit !== "" && !/[A-Za-z]/.test(typed.unit))) {
        failed([`${id}: '${field.value}' is not a number, or a number with a unit (e.g. '${sig(value)} ${unitText}')`]);
        return;
      }
      if (typed.unit) {
        // A unit typed with the number: sent as typed (the server checks its dimension);
        // the slider follows where the page can convert it.
        setPath(state.config, c.path, c.kind === "number" ? text : `${typed.number} ${typed.unit}`);
        const f = unitFactor(typed.unit);
        if (f !== null && shown !== null) slider.value = toPosition(typed.number * f * shown.scale + shown.offset);
      } else {
        setPath(state.config, c.path, joinQuantity(typed.number, sendUnit));
        slider.value = toPosition(typed.number);
      }
      slider.setAttribute("aria-valuetext", `${field.value} ${typed.unit ? "" : unitText}`.trim());
      edited();
      requestDeploy();
    });
  }
  document.getElementById("inertia-note").textContent = hasInertia
    ? "The inertia acts in the dynamic method only; the quasi-static methods ignore it."
    : "No inertia slider: this config has no [load] inertia (the quasi-static methods do not use it; add it and method \"dynamic\" in the config for the dynamic method).";
  buildTemperatureField();
  renderFitReference();
}

// The temperatures are shown in the display system's unit too (degF in US units), each
// converted from the unit the config wrote it in; a bare number typed there is in that
// unit, and another unit may be typed with the number (25 degC).
function buildTemperatureField() {
  const temps = getPath(state.config, ["analysis", "temperatures"]) || ["25 degC"];
  const shown = unitOf("temperature");
  const field = document.getElementById("temperatures");
  const lab = document.getElementById("temperatures-label");
  const values = temps.map((t) => {
    const q = splitQuantity(t);
    const c = q === null ? null : toCelsius(q.number, q.unit);
    return c === null ? String(t) : sig(c * shown.scale + shown.offset);
  });
  lab.textContent = `temperatures [${shown.unit}], comma-separated`;
  field.value = values.join(", ");
  field.dataset.unit = shown.unit;
  document.getElementById("temperatures-help").textContent =
    `Bare numbers are ${shown.unit}; another unit may be written with the number (e.g. ${shown.unit === "degF" ? "25 degC" : "77 degF"}).`;
}

function onTemperatures(e) {
  const items = e.target.value.split(",").map((s) => s.trim()).filter((s) => s.length);
  const unit = e.target.dataset.unit || "degC";
  if (!state.config.analysis) state.config.analysis = {};
  state.config.analysis.temperatures = items.map((s) => (/[a-zA-Z]/.test(s) ? s : `${s} ${unit}`));
  requestDeploy();
}

// A config with no [output] units whose temperatures are all written in degF is shown in
// US units by default ("default" in the selector), as its author thinks in them.
function defaultSystem(config) {
  if (getPath(config, ["output", "units"])) return null;
  const temps = getPath(config, ["analysis", "temperatures"]) || [];
  const degf = temps.length > 0 && temps.every((t) => { const q = splitQuantity(t); return q && /degF|°F/.test(q.unit || ""); });
  return degf ? "us" : null;
}

// ---------------------------------------------------------------- requests and state

function showErrors(errors) {
  document.getElementById("errors").textContent = errors.length ? "error: " + errors.join("\nerror: ") : "";
}

// An error: say it, and mark the results on the page as stale (they are the last valid case).
function failed(errors) {
  showErrors(errors);
  state.stale = true;
  document.getElementById("results-section").dataset.stale = "true";
}

async function postJson(url, body) {
  return fetch(url, { method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify(body) });
}

function chosenSystem(config) {
  return state.choice !== "config" ? state.choice : defaultSystem(config);
}

function deployBody(config) {
  const body = { config };
  const system = chosenSystem(config);
  if (system) body.units = system;
  return body;
}

async function requestDeploy() {
  if (state.inFlight) { state.pending = true; return; }
  state.inFlight = true;
  state.pending = false;
  const sent = JSON.parse(JSON.stringify(state.config));
  const wing = isWingConfig(sent); // a wing file: its own endpoint and page (wing.js)
  try {
    const r = await postJson(wing ? "/api/wing" : "/api/deploy", deployBody(sent));
    const body = await r.json();
    if (r.ok) {
      state.response = wing ? null : body;
      state.wing = wing ? body : null;
      state.sentConfig = sent;
      if (body.units) state.units = body.units;
      if (body.display_units) state.displayUnits = body.display_units;
      state.stale = false;
      document.getElementById("results-section").dataset.stale = "false";
      showErrors([]);
      // The inputs follow the results' unit system: rebuilt when it changed.
      if (state.builtFor !== state.displayUnits) buildControls();
      if (wing) renderWing(); else render();
      if (state.fit) renderFit(); // the display units may have changed
      saveToUrl();
    } else failed(body.errors || [`HTTP ${r.status}`]);
  } catch (e) {
    failed([String(e)]);
  } finally {
    state.inFlight = false;
    state.requests += 1;
    document.body.dataset.requests = String(state.requests);
    if (state.pending) requestDeploy();
  }
}

// ---------------------------------------------------------------- the case in the URL

function encodeCase(obj) {
  const bytes = new TextEncoder().encode(JSON.stringify(obj));
  let text = "";
  for (const b of bytes) text += String.fromCharCode(b);
  return btoa(text).replace(/\+/g, "-").replace(/\//g, "_").replace(/=+$/, "");
}

function decodeCase(text) {
  const b64 = text.replace(/-/g, "+").replace(/_/g, "/");
  const raw = atob(b64 + "===".slice((b64.length + 3) % 4));
  return JSON.parse(new TextDecoder().decode(Uint8Array.from(raw, (c) => c.charCodeAt(0))));
}

function saveToUrl() {
  const params = new URLSearchParams();
  params.set("case", encodeCase(state.sentConfig));
  if (state.choice !== "config") params.set("units", state.choice);
  if (state.pinned) params.set("a", encodeCase(state.pinned.config));
  history.replaceState(null, "", "#" + params.toString());
}

// ---------------------------------------------------------------- rendering

function narrow() { return window.innerWidth < NARROW; }

// A plot's layout: the title left-aligned above the plot and the legend below it, so that
// neither the toolbar (drawn down the right edge, and none on a phone) covers a title nor
// a legend takes the plot's width: the plot keeps at least 80 % of a phone's 390 px.
// The height grows with the legend's rows (estimated from its longest entry).
function layout(elementId, title, xlabel, ylabel, names, extra = {}) {
  const width = document.getElementById(elementId).clientWidth || 600;
  const small = narrow();
  const longest = Math.max(8, ...names.map((n) => n.length));
  const perRow = Math.max(1, Math.floor((width - 20) / (40 + 6.4 * longest)));
  const rows = names.length ? Math.ceil(names.length / perRow) : 0;
  const base = small ? 300 : 340;
  // On a phone a long title breaks at its parenthesis, onto a second line.
  const text = small ? title.replace(" (", "<br>(") : title;
  const lines = text.split("<br>").length;
  const top = 18 + 22 * lines;
  const bottom = 52 + 20 * rows;
  return {
    title: { text, x: 0, xref: "paper", xanchor: "left", y: 1, yref: "container", yanchor: "top", pad: { t: 10 },
      font: { size: small ? 15 : 17 } },
    height: base + top + bottom,
    margin: { t: top, r: small ? 8 : 44, b: bottom, l: small ? 48 : 64 },
    xaxis: { title: { text: xlabel } }, yaxis: { title: { text: ylabel } },
    legend: { orientation: "h", x: 0, xanchor: "left", y: 0, yref: "container", yanchor: "bottom", font: { size: 11 } },
    ...extra,
  };
}
// No "share" button: it would upload the chart to Plotly's cloud (the explorer makes no
// network requests); the selection tools have nothing to select here. The toolbar runs
// down the right edge (never over a title); a phone gets none (pinch and drag zoom).
function plotConfig() {
  return {
    responsive: true, displaylogo: false, displayModeBar: narrow() ? false : "hover",
    modeBarButtonsToRemove: ["sendChartToCloud", "sendDataToCloud", "lasso2d", "select2d"],
  };
}
function draw(elementId, traces, title, xlabel, ylabel, extra = {}) {
  const names = traces.filter((t) => t.showlegend !== false && t.name).map((t) => t.name);
  const config = plotConfig();
  const lay = layout(elementId, title, xlabel, ylabel, names, extra);
  lay.modebar = { orientation: "v" };
  Plotly.react(elementId, traces, lay, config);
}

// A temperature's colour (degC), by its value over the page's range [lo, hi].
function temperatureColor(t, lo, hi) {
  const x = hi > lo ? Math.min(1, Math.max(0, (t - lo) / (hi - lo))) : 0;
  const scaled = x * (TEMPERATURE_ANCHORS.length - 1);
  const i = Math.min(Math.floor(scaled), TEMPERATURE_ANCHORS.length - 2);
  const f = scaled - i;
  const rgb = TEMPERATURE_ANCHORS[i].map((a, k) => Math.round(a + f * (TEMPERATURE_ANCHORS[i + 1][k] - a)));
  return `rgb(${rgb.join(",")})`;
}
// The range of the temperatures on the page (the current case and the pinned A).
function pageRange() {
  const temps = [];
  for (const body of [state.response, state.pinned && state.pinned.response]) {
    if (body) temps.push(...body.prediction.cases.map((c) => c.temperature_C));
  }
  return temps.length ? [Math.min(...temps), Math.max(...temps)] : [0, 0];
}

function caseTemperature(c) { return `${sig(show("temperature", c.temperature_C))} ${label("temperature")}`; }

// A case that does not reach the latch: it stalls (quasi-static: the spring torque falls
// to the friction), sticks (dynamic: stick-slip holds it), or has no solution.
function notDeployed(r) {
  return r !== undefined && r !== null && (r.deployment_time_s === null || r.deployment_time_s === undefined);
}
function stopAngle(r) {
  for (const key of ["stall_angle_rad", "stuck_angle_rad", "final_angle_rad"]) {
    if (r[key] !== null && r[key] !== undefined) return r[key];
  }
  return null;
}
function stallText(r) {
  const angle = stopAngle(r);
  if (angle === 0 && (r.stalled || r.stuck)) return "cannot start: friction at release >= spring torque";
  const at = angle === null ? "" : ` at ${sig((angle * 180) / Math.PI, 4)} deg`;
  if (r.stalled) return `stalls${at}`;
  if (r.stuck) return `stuck${at}`;
  return `not deployed (${r.status || "no solution"})${at}`;
}
// The short form for a legend entry: "stalls 82.3 deg", "cannot start".
function stallShort(r) {
  const angle = stopAngle(r);
  if (angle === 0 && (r.stalled || r.stuck)) return "cannot start";
  const at = angle === null ? "" : ` ${sig((angle * 180) / Math.PI, 3)} deg`;
  if (r.stalled) return `stalls${at}`;
  if (r.stuck) return `stuck${at}`;
  return "not deployed";
}

// Where and when a case stops: (time, angle [deg]). "cannot start" at t = 0; a dynamic
// run stuck at a finite time at that time; a quasi-static stall is approached
// asymptotically (the speed falls to zero at the stall angle): the first time the curve
// comes within 0.5 % of the stall angle, else the end of the time axis.
function stopPoint(r, time, angles) {
  const angle = stopAngle(r);
  if (angle === null) return null;
  const deg = (angle * 180) / Math.PI;
  if (angle === 0) return [0, 0];
  if (r.stuck && r.stuck_time_s !== null && r.stuck_time_s !== undefined && Number.isFinite(r.stuck_time_s)) {
    return [r.stuck_time_s, deg];
  }
  const i = angles.findIndex((a) => a !== null && a >= 0.995 * deg);
  return [time[i >= 0 ? i : time.length - 1], deg];
}

function angleTraces(body, prefix, faded, range) {
  const doc = body.prediction;
  const time = body.trajectories.time_s;
  const traces = [];
  let marked = false;
  doc.methods.forEach((m) => {
    doc.cases.forEach((c, j) => {
      const r = c[m] || {};
      const stalled = notDeployed(r);
      const color = temperatureColor(c.temperature_C, range[0], range[1]);
      const angles = body.trajectories.methods[m].angle_rad[j].map((a) => (a === null ? null : (a * 180) / Math.PI));
      traces.push({
        x: time, y: angles,
        name: `${prefix}${caseTemperature(c)}, ${m}${stalled ? ": " + stallShort(r) : ""}`,
        mode: "lines",
        opacity: faded ? 0.45 : 1,
        line: { color, dash: DASH[m] || "dashdot", width: faded ? 1.5 : 2.2 },
      });
      const point = stalled ? stopPoint(r, time, angles) : null;
      if (point !== null) {
        // Where it stops, in its temperature's colour; the line's legend entry names it.
        traces.push({
          x: [point[0]], y: [point[1]], mode: "markers", showlegend: false,
          name: `${prefix}${caseTemperature(c)}, ${m}: ${stallText(r)}`,
          marker: { symbol: "x-thin-open", size: 14, color, line: { width: 3, color } }, opacity: faded ? 0.45 : 1,
          cliponaxis: false, // a cross at t = 0 ("cannot start") shows whole on the axis
          hovertemplate: `${escapeHtml(stallText(r))}<extra>${escapeHtml(caseTemperature(c))}, ${m}</extra>`,
        });
        marked = true;
      }
    });
  });
  if (marked && !prefix.startsWith("A")) {
    // One legend entry says what a cross is (the lines' entries say where).
    traces.push({ x: [null], y: [null], mode: "markers", name: "x: where it stops (cannot start: at t = 0)",
      marker: { symbol: "x-thin-open", size: 12, color: "#333", line: { width: 2.5, color: "#333" } } });
  }
  return traces;
}

function sweepTraces(body, prefix, faded) {
  const doc = body.prediction;
  const sweep = body.sweep;
  const x = sweep.temperature_C.map((t) => show("temperature", t));
  const traces = [];
  const finite = doc.methods.flatMap((m) => sweep.methods[m].deployment_time_s.filter((v) => v !== null));
  const top = finite.length ? Math.max(...finite) * 1.05 : 1;
  doc.methods.forEach((m, k) => {
    const y = sweep.methods[m].deployment_time_s;
    traces.push({
      x, y, name: `${prefix}${m}`, mode: "lines+markers", opacity: faded ? 0.45 : 1,
      line: { dash: DASH[m] || "dashdot", color: METHOD_COLORS[m] || "#555" },
      marker: { color: METHOD_COLORS[m] || "#555", size: 5 },
    });
    const stallX = x.filter((_, i) => y[i] === null);
    if (stallX.length) {
      // Stalled temperatures have no deployment time: marked along the top, not dropped.
      traces.push({
        // One row per method above the curves, in the method's colour.
        x: stallX, y: stallX.map(() => top * (1 + 0.05 * k)), mode: "markers", name: `${prefix}${m}: stalls (no deployment)`,
        marker: { symbol: "x", size: 10, color: METHOD_COLORS[m] || "#b00020" }, opacity: faded ? 0.45 : 1,
        hovertemplate: `stalls at %{x} ${label("temperature")}<extra>${m}</extra>`,
      });
    }
  });
  return traces;
}

function render() {
  const body = state.response;
  const doc = body.prediction;
  const pinned = state.pinned;
  const pb = pinned ? "B: " : "";
  const range = pageRange();
  const angle = angleTraces(body, pb, false, range);
  const sweep = sweepTraces(body, pb, false);
  if (pinned) {
    angle.push(...angleTraces(pinned.response, "A: ", true, range));
    sweep.push(...sweepTraces(pinned.response, "A: ", true));
  }
  const suffix = pinned ? " (B solid, pinned A faded)" : "";
  const ends = [body, pinned && pinned.response].filter(Boolean).map((b) => b.trajectories.time_s[b.trajectories.time_s.length - 1]);
  draw("angle-plot", angle, `Deployed angle against time${suffix}`, "time since release [s]", "angle [deg]",
    { xaxis: { title: { text: "time since release [s]" }, range: [0, Math.max(...ends)], zeroline: false } });
  draw("sweep-plot", sweep, `Deployment time against temperature${suffix}`, `temperature [${label("temperature")}]`, "deployment time [s]",
    { xaxis: { title: { text: `temperature [${label("temperature")}]` }, zeroline: false } });
  renderPlaceholder();
  renderTable(doc, pinned ? pinned.response.prediction : null);
  renderGroundTest(doc);
  renderMethodsNote(doc.methods);
  const warnings = document.getElementById("warnings");
  warnings.innerHTML = "";
  for (const w of doc.warnings) {
    const div = document.createElement("div");
    div.textContent = (w.method ? `[${w.method}] ` : "") + (w.display_message ?? w.message);
    warnings.appendChild(div);
  }
  document.getElementById("timing").textContent = `Last computation ${sig(body.compute_ms, 3)} ms on the server.`;
  renderCompareSummary();
}

// A [load] marked placeholder = true (a fit's stand-in): a banner until the spring
// torques or the travel are edited here (which drops the mark), or the file is fixed.
function renderPlaceholder() {
  const banner = document.getElementById("placeholder-banner");
  banner.hidden = !(state.sentConfig && getPath(state.sentConfig, ["load", "placeholder"]) === true);
}

// With [load.gravity]: flight (0 g) against the ground test as configured (docs/model.md).
function renderGroundTest(doc) {
  const box = document.getElementById("ground-test");
  const ground = doc.ground_test;
  box.hidden = !ground;
  if (!ground) return;
  const offload = sig(100 * ground.offload, 3);
  document.getElementById("ground-test-heading").textContent =
    `Flight (0 g) against ground test (1 g, ${offload} % offloaded)`;
  document.getElementById("ground-test-note").textContent =
    `The results above are the ground test as configured: ${sig(show("mass", ground.mass_kg))} ${label("mass")} at ` +
    `${sig(show("length", ground.cg_radius_m))} ${label("length")} from the hinge, ${offload} % of the weight offloaded. ` +
    `Gravity torque m g r (1 - offload) sin(theta_0 + phi), positive opposing deployment: ` +
    `${sig(show("torque", ground.torque_at_release_Nm), 4)} ${label("torque")} at release, ` +
    `${sig(show("torque", ground.torque_at_latch_Nm), 4)} ${label("torque")} at the latch.`;
  const tl = label("temperature");
  document.querySelector("#ground-table thead").innerHTML =
    `<tr><th scope="col">T [${tl}]</th><th scope="col">method</th><th scope="col">flight t [s]</th>` +
    '<th scope="col">test t [s]</th><th scope="col">test - flight [s]</th><th scope="col">rel. [%]</th></tr>';
  const text = (v) => (v === null || v === undefined ? "stalls" : sig(v));
  document.querySelector("#ground-table tbody").innerHTML = ground.cases.map((c, i) =>
    doc.methods.map((m) => {
      const b = c[m];
      const d = b.test_minus_flight_s;
      const rel = b.relative === null ? "-" : (b.relative > 0 ? "+" : "") + (100 * b.relative).toFixed(1);
      return `<tr><th scope="row" class="num">${sig(show("temperature", c.temperature_C))}</th><td>${escapeHtml(m)}</td>` +
        `<td class="num" data-case="${i}" data-ground-key="${m}.flight">${text(b.flight_deployment_time_s)}</td>` +
        `<td class="num" data-case="${i}" data-ground-key="${m}.test">${text(b.test_deployment_time_s)}</td>` +
        `<td class="num" data-case="${i}" data-ground-key="${m}.difference">${d === null ? "-" : (d > 0 ? "+" : "") + sig(d, 4)}</td>` +
        `<td class="num">${rel}</td></tr>`;
    }).join("")).join("");
}

function renderMethodsNote(methods) {
  const box = document.getElementById("methods-note");
  box.innerHTML = "<p>Each change is computed on the server with the configured methods:</p><ul>" +
    methods.map((m) => `<li>${escapeHtml(METHOD_NOTES[m] || m)}</li>`).join("") + "</ul>";
}

// Columns of the results table: [key path in a case, kind, heading].
function tableColumns(methods) {
  const cols = [];
  for (const m of methods) {
    cols.push([`${m}.deployment_time_s`, "time", `${m}: t`]);
    cols.push([`${m}.end_speed_rad_s`, "angular_speed", `${m}: end speed`]);
  }
  cols.push(["damping_rate_Nms_per_rad", "damping_rate", "BECD"]);
  cols.push(["friction_Nm", "torque", "FECD"]);
  return cols;
}

function caseValue(c, key) { return getPath(c, key.split(".")); }

function cellText(c, key, kind) {
  const v = caseValue(c, key);
  const method = key.includes(".") ? key.split(".")[0] : null;
  if ((v === null || v === undefined) && method && notDeployed(c[method])) return stallText(c[method]);
  return sig(show(kind, v));
}

function renderTable(doc, pinnedDoc) {
  const head = document.querySelector("#results thead");
  const rows = document.querySelector("#results tbody");
  const cols = tableColumns(doc.methods);
  const tl = label("temperature");
  const unitText = (kind) => `[${label(kind)}]`;
  if (!pinnedDoc) {
    head.innerHTML = `<tr><th scope="col">T [${tl}]</th>` +
      cols.map(([, kind, name]) => `<th scope="col">${name} ${unitText(kind)}</th>`).join("") + "</tr>";
  } else {
    head.innerHTML = `<tr><th scope="col" rowspan="2">T [${tl}]</th>` +
      cols.map(([, kind, name]) => `<th scope="colgroup" colspan="3">${name} ${unitText(kind)}</th>`).join("") +
      "</tr><tr>" + cols.map(() => '<th scope="col">A</th><th scope="col">B</th><th scope="col">B - A</th>').join("") + "</tr>";
  }
  rows.innerHTML = doc.cases.map((c, i) => {
    const match = pinnedDoc ? pinnedDoc.cases.find((a) => Math.abs(a.temperature_C - c.temperature_C) < 1e-9) : null;
    let html = `<tr><th scope="row" class="num" data-case="${i}" data-key="temperature">${sig(show("temperature", c.temperature_C))}</th>`;
    for (const [key, kind] of cols) {
      const method = key.includes(".") ? key.split(".")[0] : null;
      const stalled = method && notDeployed(c[method]) && caseValue(c, key) === null;
      const current = `<td class="num${stalled ? " stalled" : ""}" data-case="${i}" data-key="${key}">${escapeHtml(cellText(c, key, kind))}</td>`;
      if (!pinnedDoc) { html += current; continue; }
      const a = match ? caseValue(match, key) : undefined;
      const b = caseValue(c, key);
      const diff = a !== null && a !== undefined && b !== null && b !== undefined ? showDiff(kind, b - a) : null;
      const aText = match ? cellText(match, key, kind) : "-";
      html += `<td class="num pinned" data-case="${i}" data-pinned-key="${key}">${escapeHtml(aText)}</td>` + current +
        `<td class="num diff" data-case="${i}" data-diff-key="${key}">${diff === null ? "-" : (diff > 0 ? "+" : "") + sig(diff, 4)}</td>`;
    }
    return html + "</tr>";
  }).join("");
}

// ---------------------------------------------------------------- compare (A pinned, B current)

function flatten(obj, prefix = "", out = {}) {
  for (const [k, v] of Object.entries(obj || {})) {
    const key = prefix ? `${prefix}.${k}` : k;
    if (v !== null && typeof v === "object" && !Array.isArray(v)) flatten(v, key, out);
    else out[key] = Array.isArray(v) ? v.join(", ") : String(v);
  }
  return out;
}

function renderCompareSummary() {
  const box = document.getElementById("compare-summary");
  if (!state.pinned) {
    box.textContent = "Pin a case, then change the inputs: the current case (B) is drawn over A in every plot and table, with B - A.";
    return;
  }
  const a = flatten(state.pinned.config);
  const b = flatten(state.sentConfig);
  const keys = [...new Set([...Object.keys(a), ...Object.keys(b)])].sort();
  const changed = keys.filter((k) => a[k] !== b[k]);
  box.innerHTML = `<p>A: pinned (${escapeHtml(state.pinned.source)}). B: the current inputs. Inputs that differ:</p>` +
    (changed.length
      ? "<ul id=\"compare-diffs\">" + changed.map((k) => `<li><code>${escapeHtml(k)}</code>: A ${escapeHtml(a[k] ?? "(absent)")} &rarr; B ${escapeHtml(b[k] ?? "(absent)")}</li>`).join("") + "</ul>"
      : "<p id=\"compare-diffs\">none (B equals A)</p>");
}

function pin() {
  if (!state.response) return;
  state.pinned = {
    config: JSON.parse(JSON.stringify(state.sentConfig)),
    response: JSON.parse(JSON.stringify(state.response)),
    source: document.getElementById("source").textContent || "case",
  };
  document.getElementById("unpin").disabled = false;
  render();
  saveToUrl();
}

function unpin() {
  state.pinned = null;
  document.getElementById("unpin").disabled = true;
  if (state.response) { render(); saveToUrl(); }
}

// Pin a config given by a link: compute it once, then hold it as A.
async function pinConfig(config) {
  const r = await postJson("/api/deploy", deployBody(config));
  if (!r.ok) return;
  const body = await r.json();
  state.pinned = { config, response: body, source: "from the link" };
  document.getElementById("unpin").disabled = false;
}

// ---------------------------------------------------------------- loading and exporting

async function loadExample(which, note = "") {
  const r = await fetch(`/api/example?which=${which}`);
  const body = await r.json();
  useConfig(body.config, body.source + note, body.units, body.display_units);
}

function useConfig(config, source, units, system) {
  state.config = config;
  setMode(config);
  if (units && state.choice === "config" && !defaultSystem(config)) {
    state.units = units;
    if (system) state.displayUnits = system;
  }
  document.getElementById("source").textContent = source;
  buildControls();
  requestDeploy();
}

async function download(url, filename) {
  const r = await postJson(url, url === "/api/report" ? deployBody(state.config) : { config: state.config });
  if (!r.ok) { const body = await r.json(); failed(body.errors || [`HTTP ${r.status}`]); return; }
  const blob = await r.blob();
  const a = document.createElement("a");
  a.href = URL.createObjectURL(blob);
  a.download = filename;
  document.body.appendChild(a);
  a.click();
  a.remove();
}

async function copyLink() {
  const button = document.getElementById("copy-link");
  try {
    await navigator.clipboard.writeText(location.href);
    button.textContent = "Link copied";
  } catch (e) {
    button.textContent = "Link is in the address bar";
  }
  setTimeout(() => { button.textContent = "Copy link to this case"; }, 2500);
}

// ---------------------------------------------------------------- fit from the bench

function drawFit(elementId, traces, title, xlabel, ylabel, yrange = null) {
  const extra = { xaxis: { title: { text: xlabel }, zeroline: false } };
  if (yrange) extra.yaxis = { title: { text: ylabel }, range: yrange };
  draw(elementId, traces, title, xlabel, ylabel, extra);
}

function band(x, curve, name, color) {
  if (!curve.low || !curve.high) return [];
  return [{
    x: [...x, ...[...x].reverse()], y: [...curve.high, ...[...curve.low].reverse()], fill: "toself",
    fillcolor: color, opacity: 0.18, line: { width: 0 }, name: `${name} 95 % band`, hoverinfo: "skip", mode: "lines",
  }];
}

function renderFit() {
  const body = state.fit;
  const curves = body.curves;
  const tk = (v) => show("torque", v);
  const torque = [];
  const fitTemps = curves.torque_speed.map((l) => l.temperature_C);
  const [lo, hi] = [Math.min(...fitTemps), Math.max(...fitTemps)];
  curves.torque_speed.forEach((line) => {
    const color = temperatureColor(line.temperature_C, lo, hi);
    const t = `${sig(show("temperature", line.temperature_C))} ${label("temperature")}`;
    torque.push({ x: line.speed_rad_s, y: line.torque_Nm.map(tk), mode: "markers", name: `${t} tests`, marker: { color, size: 7 } });
    torque.push({
      x: line.line_speed_rad_s, y: line.line_torque_Nm.map(tk), mode: "lines", line: { color },
      name: `${t}: BECD ${sig(show("damping_rate", line.damping_rate_Nms_per_rad.value), 4)}, FECD ${sig(tk(line.friction_Nm.value), 3)}`,
    });
    const out = line.outlier.map((o, i) => (o ? i : -1)).filter((i) => i >= 0);
    if (out.length) {
      torque.push({ x: out.map((i) => line.speed_rad_s[i]), y: out.map((i) => tk(line.torque_Nm[i])), mode: "markers",
        name: `outlier (${t})`, marker: { size: 15, color: "rgba(0,0,0,0)", line: { color: "black", width: 1.5 } } });
    }
  });
  drawFit("fit-torque-plot", torque, "Drop test: drive torque against speed (Fig. 8)", "speed [rad/s]", `drive torque [${label("torque")}]`);

  const temps = curves.torque_speed.map((l) => show("temperature", l.temperature_C));
  const grid = curves.laws.temperature_C.map((t) => show("temperature", t));
  const perTemp = (key, kind) => {
    const est = curves.torque_speed.map((l) => l[key]);
    return {
      x: temps, y: est.map((e) => show(kind, e.value)), mode: "markers", name: "per temperature (95 %)",
      marker: { color: fitTemps.map((t) => temperatureColor(t, lo, hi)), size: 8 },
      error_y: {
        type: "data", symmetric: false,
        array: est.map((e) => (e.ci95 ? showDiff(kind, e.ci95[1] - e.value) : 0)),
        arrayminus: est.map((e) => (e.ci95 ? showDiff(kind, e.value - e.ci95[0]) : 0)),
      },
    };
  };
  // Laws in black and grey: none of the temperatures' colours.
  const lawColors = { linear: "#111111", resistivity: "#7b5ea7" };
  const damping = [perTemp("damping_rate_Nms_per_rad", "damping_rate")];
  for (const [name, curve] of Object.entries(curves.laws.damping_rate)) {
    const conv = { value: curve.value.map((v) => show("damping_rate", v)),
      low: curve.low && curve.low.map((v) => show("damping_rate", v)), high: curve.high && curve.high.map((v) => show("damping_rate", v)) };
    damping.push(...band(grid, conv, `${name} law`, lawColors[name] || "#555"));
    damping.push({ x: grid, y: conv.value, mode: "lines", name: `${name} law`, line: { color: lawColors[name] || "#555", dash: name === "linear" ? "solid" : "dash" } });
  }
  // The y range holds the per-temperature intervals and the laws, not a wide band (a law
  // that misses the values has its band widened by the scatter).
  const span = (traces) => {
    const ys = traces.filter((t) => t.fill !== "toself").flatMap((t) => [...t.y, ...(t.error_y ? t.y.map((y, i) => y + t.error_y.array[i]) : []),
      ...(t.error_y ? t.y.map((y, i) => y - t.error_y.arrayminus[i]) : [])]).filter((v) => v !== null && Number.isFinite(v));
    const lo = Math.min(...ys); const hi = Math.max(...ys); const pad = 0.15 * (hi - lo || Math.abs(hi) || 1);
    return [lo - pad, hi + pad];
  };
  drawFit("fit-damping-plot", damping, "Damping rate BECD against temperature", `temperature [${label("temperature")}]`,
    `BECD [${label("damping_rate")}]`, span(damping));
  const friction = [perTemp("friction_Nm", "torque")];
  if (curves.laws.friction) {
    const f = curves.laws.friction;
    const conv = { value: f.value.map(tk), low: f.low && f.low.map(tk), high: f.high && f.high.map(tk) };
    friction.push(...band(grid, conv, "line", "#111111"));
    friction.push({ x: grid, y: conv.value, mode: "lines", name: "line FECD(T)", line: { color: "#111111" } });
  }
  drawFit("fit-friction-plot", friction, "Friction FECD against temperature", `temperature [${label("temperature")}]`,
    `FECD [${label("torque")}]`);

  const ci = (e, kind) => (e.ci95 ? `[${sig(show(kind, e.ci95[0]), 4)}, ${sig(show(kind, e.ci95[1]), 4)}]` : "-");
  document.querySelector("#fit-table thead").innerHTML =
    `<tr><th scope="col">T [${label("temperature")}]</th><th scope="col">points</th><th scope="col">BECD [${label("damping_rate")}]</th><th scope="col">95 % interval</th><th scope="col">FECD [${label("torque")}]</th><th scope="col">95 % interval</th></tr>`;
  document.querySelector("#fit-table tbody").innerHTML = body.fit.temperatures.map((t, i) =>
    `<tr><th scope="row" class="num">${sig(show("temperature", t.temperature_C))}</th><td class="num">${t.n_points}</td>` +
    `<td class="num" data-fit="${i}" data-key="damping_rate_Nms_per_rad">${sig(show("damping_rate", t.damping_rate_Nms_per_rad))}</td>` +
    `<td class="num">${ci({ value: t.damping_rate_Nms_per_rad, ci95: t.damping_rate_ci95_Nms_per_rad }, "damping_rate")}</td>` +
    `<td class="num" data-fit="${i}" data-key="friction_Nm">${sig(show("torque", t.friction_Nm))}</td>` +
    `<td class="num">${ci({ value: t.friction_Nm, ci95: t.friction_ci95_Nm }, "torque")}</td></tr>`).join("");
  const laws = body.fit.temperature_laws;
  const lawRows = [];
  if (laws) {
    const lin = laws.damping_rate.linear;
    if (lin) {
      lawRows.push(["B_ref (linear law, at " + sig(show("temperature", lin.reference_temperature_C)) + " " + label("temperature") + ")", sig(show("damping_rate", lin.damping_rate_ref_Nms_per_rad)), ci({ value: 0, ci95: lin.damping_rate_ref_Nms_per_rad_ci95 }, "damping_rate"), label("damping_rate"), "b_ref"]);
      lawRows.push(["c (linear law)", sig(show("per_kelvin", lin.temperature_coefficient_per_K)), ci({ value: 0, ci95: lin.temperature_coefficient_per_K_ci95 }, "per_kelvin"), label("per_kelvin"), "c"]);
    }
    if (laws.friction) {
      lawRows.push(["FECD slope", sig(show("torque_per_kelvin", laws.friction.slope_Nm_per_K)), ci({ value: 0, ci95: laws.friction.slope_Nm_per_K_ci95 }, "torque_per_kelvin"), label("torque_per_kelvin"), "slope"]);
      lawRows.push([label("temperature") === "degF" ? "FECD at 32 degF (0 degC)" : "FECD at 0 degC", sig(show("torque", laws.friction.at_0C_Nm)), ci({ value: 0, ci95: laws.friction.at_0C_Nm_ci95 }, "torque"), label("torque"), "at_0C"]);
    }
  }
  document.querySelector("#fit-laws thead").innerHTML = '<tr><th scope="col">parameter</th><th scope="col">value</th><th scope="col">95 % interval</th><th scope="col">unit</th></tr>';
  document.querySelector("#fit-laws tbody").innerHTML = lawRows.map(([n, v, c, u, key]) =>
    `<tr><th scope="row">${escapeHtml(n)}</th><td class="num" data-law="${key}">${v}</td><td class="num">${c}</td><td>${escapeHtml(u)}</td></tr>`).join("");
  const summary = laws ? laws.comparison.statement : "one temperature only: no law over temperature";
  document.getElementById("fit-summary").textContent = `${body.fit.source}: ${body.fit.temperatures.length} temperatures fitted (noise model: ${body.fit.noise_model}); ${summary}.`;
  const warn = document.getElementById("fit-warnings");
  warn.innerHTML = "";
  for (const w of [...body.fit.warnings.map((x) => x.message), ...body.fit.bad_rows.map((b) => b.message || JSON.stringify(b))]) {
    const div = document.createElement("div");
    div.className = "note";
    div.textContent = "warning: " + w;
    warn.appendChild(div);
  }
  const use = document.getElementById("fit-use");
  use.disabled = body.config === null;
  use.title = body.export_error ? `cannot use: ${body.export_error}` : "replace [damper] and [gearbox] by the fitted ECD (N = 1), keeping [load]";
}

// The fit's reference temperature in the display system's unit (degF in US units): the
// field converts when the system changes, and a unit may be typed with the number.
function renderFitReference() {
  const field = document.getElementById("fit-reference");
  const unit = unitOf("temperature").unit;
  const previous = field.dataset.unit || "degC";
  if (previous !== unit) {
    const q = splitQuantity(field.value.trim());
    const c = q === null ? null : toCelsius(q.number, q.unit || previous);
    if (c !== null) field.value = sig(show("temperature", c));
    field.dataset.unit = unit;
  }
  document.getElementById("fit-reference-label").textContent = `reference temperature [${unit}]`;
}

// The reference temperature in degC (the API's unit), or null if it is not one.
function fitReference() {
  const field = document.getElementById("fit-reference");
  const q = splitQuantity(field.value.trim());
  if (q === null || (q.unit !== "" && !/[A-Za-z]/.test(q.unit))) return null;
  const c = toCelsius(q.number, q.unit || field.dataset.unit || "degC");
  return c === null || !Number.isFinite(c) ? null : c;
}

async function runFit(file) {
  const errors = document.getElementById("fit-errors");
  errors.textContent = "";
  const reference = fitReference();
  if (reference === null) {
    errors.textContent = `error: reference temperature: '${document.getElementById("fit-reference").value}' is not a temperature (a number in ${unitOf("temperature").unit}, or with its unit, e.g. 25 degC)`;
    return;
  }
  try {
    const body = {
      csv: await file.text(), filename: file.name || "drop_test.csv",
      noise: document.getElementById("fit-noise").value, reference_temperature: reference,
    };
    if (state.config) body.config = state.config;
    const system = state.config ? chosenSystem(state.config) : (state.choice !== "config" ? state.choice : null);
    if (system) body.units = system;
    const r = await postJson("/api/fit/drop-test", body);
    const answer = await r.json();
    if (r.ok) {
      state.fit = answer;
      document.getElementById("fit-results").hidden = false;
      renderFit();
    } else {
      errors.textContent = "error: " + (answer.errors || [`HTTP ${r.status}`]).join("\nerror: ");
    }
  } catch (e) {
    errors.textContent = "error: " + String(e);
  } finally {
    state.fits += 1;
    document.body.dataset.fits = String(state.fits);
  }
}

function useFit() {
  if (!state.fit || !state.fit.config) return;
  // The case sent with the fit, with the fitted ECD in place of [damper] and [gearbox]
  // (the server's answer, as ecdsim fit drop-test -o FILE --config CASE writes it).
  const config = JSON.parse(JSON.stringify(state.fit.config));
  useConfig(config, `ECD fitted from ${state.fit.fit.source}`);
}

// ---------------------------------------------------------------- wiring

document.getElementById("temperatures").addEventListener("change", onTemperatures);
document.getElementById("load-example").addEventListener("click", () => loadExample("paper"));
document.getElementById("load-start").addEventListener("click", () => loadExample("start"));
document.getElementById("download-toml").addEventListener("click", () => download("/api/config.toml", "ecdsim-config.toml"));
document.getElementById("download-report").addEventListener("click", () => download("/api/report", "ecdsim-report.html"));
document.getElementById("copy-link").addEventListener("click", copyLink);
document.getElementById("pin").addEventListener("click", pin);
document.getElementById("unpin").addEventListener("click", unpin);
document.getElementById("units").addEventListener("change", (e) => {
  state.choice = e.target.value;
  requestDeploy();
});
document.getElementById("upload").addEventListener("change", async (e) => {
  const file = e.target.files[0];
  if (!file) return;
  const r = await postJson("/api/config/parse", { toml: await file.text() });
  const body = await r.json();
  if (r.ok) useConfig(body.config, file.name, body.units, body.display_units); else failed(body.errors || [`HTTP ${r.status}`]);
});
document.getElementById("fit-file").addEventListener("change", (e) => { if (e.target.files[0]) runFit(e.target.files[0]); });
document.getElementById("fit-use").addEventListener("click", useFit);
const zone = document.getElementById("fit-section");
zone.addEventListener("dragover", (e) => { e.preventDefault(); document.getElementById("dropzone").classList.add("over"); });
zone.addEventListener("dragleave", () => document.getElementById("dropzone").classList.remove("over"));
zone.addEventListener("drop", (e) => {
  e.preventDefault();
  document.getElementById("dropzone").classList.remove("over");
  const file = e.dataTransfer && e.dataTransfer.files[0];
  if (file) runFit(file);
});

async function start() {
  const params = new URLSearchParams(location.hash.slice(1));
  const units = params.get("units");
  if (units === "si" || units === "us") { state.choice = units; document.getElementById("units").value = units; }
  if (params.has("case")) {
    let config = null;
    try { config = decodeCase(params.get("case")); } catch (e) { config = null; }
    if (config === null || typeof config !== "object" || Array.isArray(config)) {
      loadExample("start", " (the link's case could not be read: the start config instead)");
      return;
    }
    if (params.has("a")) { try { await pinConfig(decodeCase(params.get("a"))); } catch (e) { /* A is optional */ } }
    useConfig(config, "from the link");
    return;
  }
  loadExample("start");
}

// The plots' layout follows the width (legend rows, a phone's margins and toolbar).
let resizeTimer = null;
window.addEventListener("resize", () => {
  clearTimeout(resizeTimer);
  resizeTimer = setTimeout(() => { if (state.response) render(); if (state.wing) renderWing(); if (state.fit) renderFit(); }, 150);
});

start();
