// ecdsim explorer, a wing file (docs/explorer.md, "A wing"): each hinge's angle against
// time per temperature, and the unfolding wing with a time slider and play/pause.
//
// The page's helpers (app.js: state, show, label, sig, temperatureColor, draw, layout,
// plotConfig, narrow, escapeHtml) are shared. Every number arrives in SI from
// POST /api/wing; the panels' outlines are the server's (the function the CLI's shape
// strip draws): this script only scales them to the page's length unit, never computes
// geometry.
"use strict";

// One line style per hinge (the colour is the temperature's, as on every plot).
const HINGE_DASH = ["solid", "dash", "dashdot", "dot", "longdash", "longdashdot"];
// Panel fills: no temperature's hue (blue, green and red mean cold, mild and hot here).
const PANEL_FILLS = ["#a1887f", "#90a4ae", "#d4b35a", "#8d6e63", "#607d8b", "#bfa04a"];
// A whole deployment plays in this many seconds, whatever its length.
const PLAY_SECONDS = 8;
// The time slider's steps from release to the last sample. The solver's samples are
// dense where the motion changes fast (thousands per second just after release) and
// sparse later, so the slider moves in time, not by sample: each position shows the
// last of the solution's own samples at or before it (no frame is interpolated).
const TIME_STEPS = 1000;

const wingView = { caseIndex: 0, frame: 0, time: 0, playing: false, lastTick: null };
window.ecdsimWing = wingView;

function isWingConfig(config) {
  return config !== null && typeof config === "object" && !Array.isArray(config) && "wing" in config;
}

// The page's mode follows the config: a wing file hides the single hinge's inputs and
// results (and shows the wing's); anything else is the single-hinge page as before.
function setMode(config) {
  const wing = isWingConfig(config);
  document.body.dataset.mode = wing ? "wing" : "hinge";
  if (!wing) pauseWing();
}

function deg(rad) { return rad === null || rad === undefined ? null : (rad * 180) / Math.PI; }
function len(m) { return show("length", m); }

function wingCase() { return state.wing.cases[wingView.caseIndex]; }
function wingResultCase() { return state.wing.result.cases[wingView.caseIndex]; }
function wingRange() {
  const temps = state.wing.cases.map((c) => c.temperature_C);
  return [Math.min(...temps), Math.max(...temps)];
}
function wingTemperature(c) { return `${sig(show("temperature", c.temperature_C))} ${label("temperature")}`; }

// Each hinge's angle at time t, linear between the frames (for a stick event's marker).
function angleAt(c, hinge, t) {
  const times = c.time_s;
  const angles = c.angle_rad[hinge];
  if (t <= times[0]) return angles[0];
  for (let k = 1; k < times.length; k++) {
    if (times[k] >= t) {
      const f = times[k] === times[k - 1] ? 1 : (t - times[k - 1]) / (times[k] - times[k - 1]);
      return angles[k - 1] + f * (angles[k] - angles[k - 1]);
    }
  }
  return angles[angles.length - 1];
}

// ---------------------------------------------------------------- hinge angles

function wingAngleTraces() {
  const body = state.wing;
  const [lo, hi] = wingRange();
  const traces = [];
  body.cases.forEach((c, i) => {
    const color = temperatureColor(c.temperature_C, lo, hi);
    const t = wingTemperature(c);
    body.hinges.forEach((hinge, j) => {
      traces.push({
        x: c.time_s, y: c.angle_rad[j].map(deg), mode: "lines", showlegend: false,
        name: `${t}, ${hinge}`, line: { color, dash: HINGE_DASH[j % HINGE_DASH.length], width: 2 },
        hovertemplate: `${escapeHtml(t)}, ${escapeHtml(hinge)}: %{y:.4g} deg at %{x:.4g} s<extra></extra>`,
      });
    });
    const r = body.result.cases[i];
    const latches = r.latches;
    traces.push({
      x: latches.map((l) => l.time_s), y: latches.map((l) => deg(body.travel_rad[body.hinges.indexOf(l.hinge)])),
      mode: "markers", showlegend: false, name: `${t}: latches`,
      marker: { symbol: "circle", size: 9, color, line: { color: "#000", width: 1 } },
      text: latches.map((l) => l.hinge), hovertemplate: `${escapeHtml(t)}: %{text} latches at %{x:.4g} s<extra></extra>`,
    });
    const sticks = r.events.filter((e) => e.event === "stick" && e.hinge !== null && e.time_s !== null);
    if (sticks.length) {
      traces.push({
        x: sticks.map((e) => e.time_s), y: sticks.map((e) => deg(angleAt(c, body.hinges.indexOf(e.hinge), e.time_s))),
        mode: "markers", showlegend: false, name: `${t}: sticks`,
        marker: { symbol: "x", size: 10, color, line: { color: "#000", width: 1 } },
        text: sticks.map((e) => e.hinge), hovertemplate: `${escapeHtml(t)}: %{text} sticks at %{x:.4g} s<extra></extra>`,
      });
    }
  });
  // The legend: the temperatures (colour), the hinges (line style) and the marks, each once.
  const none = { x: [null], y: [null] };
  body.cases.forEach((c) => traces.push({ ...none, mode: "lines", name: wingTemperature(c),
    line: { color: temperatureColor(c.temperature_C, lo, hi), width: 3 } }));
  body.hinges.forEach((hinge, j) => traces.push({ ...none, mode: "lines", name: `hinge ${hinge}`,
    line: { color: "#333", dash: HINGE_DASH[j % HINGE_DASH.length], width: 2 } }));
  traces.push({ ...none, mode: "markers", name: "latches", marker: { symbol: "circle", size: 9, color: "#fff", line: { color: "#000", width: 1 } } });
  if (body.result.cases.some((r) => r.events.some((e) => e.event === "stick"))) {
    traces.push({ ...none, mode: "markers", name: "sticks", marker: { symbol: "x", size: 10, color: "#333" } });
  }
  return traces;
}

function cursorShape() {
  const t = wingCase().time_s[wingView.frame];
  return [{ type: "line", xref: "x", yref: "paper", x0: t, x1: t, y0: 0, y1: 1, line: { color: "#555", width: 1, dash: "dot" } }];
}

function drawWingAngles() {
  const ends = state.wing.cases.map((c) => c.time_s[c.time_s.length - 1]);
  draw("wing-angle-plot", wingAngleTraces(), "Hinge angles against time (cursor: the animation's time)",
    "time since release [s]", "deployed angle [deg]",
    { xaxis: { title: { text: "time since release [s]" }, range: [0, Math.max(...ends)], zeroline: false },
      shapes: cursorShape() });
}

// ---------------------------------------------------------------- the unfolding wing

// The plot's fixed window over the whole run of the chosen temperature (the wing does
// not jump about as it unfolds), with the spacecraft's side at x <= 0.
function shapeWindow(c) {
  let xs = [0], ys = [0];
  for (const frame of c.outlines_m) for (const panel of frame) for (const [x, y] of panel) { xs.push(x); ys.push(y); }
  const pad = 0.06 * state.wing.extent_m;
  const wall = 0.12 * state.wing.extent_m;
  return {
    x: [len(Math.min(-wall, ...xs) - pad), len(Math.max(...xs) + pad)],
    y: [len(Math.min(...ys) - pad), len(Math.max(...ys) + pad)],
    wall: len(wall),
  };
}

function latchedBy(r, t) {
  const done = new Set();
  for (const l of r.latches) if (l.time_s <= t) done.add(l.hinge);
  return done;
}

// The hinges at rest for good short of their latch (the run's stuck hinges) by time t:
// from their last stick.
function stuckBy(r, t) {
  const stuck = new Set();
  for (const h of r.stuck_hinges) {
    const sticks = r.events.filter((e) => e.event === "stick" && e.hinge === h && e.time_s !== null);
    if (sticks.length && sticks[sticks.length - 1].time_s <= t) stuck.add(h);
  }
  return stuck;
}

function hingeStatus(h, done, stuck) {
  if (done.has(h)) return "latched";
  return stuck.has(h) ? "stuck" : "moving";
}

function drawWingShape() {
  const body = state.wing;
  const c = wingCase();
  const r = wingResultCase();
  const k = wingView.frame;
  const t = c.time_s[k];
  const frame = c.outlines_m[k];
  const traces = frame.map((corners, i) => ({
    x: [...corners.map((p) => len(p[0])), len(corners[0][0])],
    y: [...corners.map((p) => len(p[1])), len(corners[0][1])],
    mode: "lines", fill: "toself", fillcolor: PANEL_FILLS[i % PANEL_FILLS.length], opacity: 0.9,
    line: { color: "#222", width: 1 }, name: body.panels[i], hoverinfo: "name",
  }));
  // Hinge i sits at panel i's inboard end, midway across it: filled once latched, a
  // cross once stuck for good, open while it moves.
  const done = latchedBy(r, t);
  const stuck = stuckBy(r, t);
  const hingeAt = (i) => [(frame[i][0][0] + frame[i][3][0]) / 2, (frame[i][0][1] + frame[i][3][1]) / 2];
  const looks = {
    latched: { symbol: "circle", size: 10, color: "#000", line: { color: "#000", width: 2 } },
    moving: { symbol: "circle", size: 10, color: "#fff", line: { color: "#000", width: 2 } },
    stuck: { symbol: "x", size: 12, color: "#b00020", line: { color: "#000", width: 1 } },
  };
  for (const status of ["latched", "moving", "stuck"]) {
    const which = body.hinges.map((h, i) => i).filter((i) => hingeStatus(body.hinges[i], done, stuck) === status);
    if (status === "stuck" && !which.length) continue;
    traces.push({
      x: which.map((i) => len(hingeAt(i)[0])), y: which.map((i) => len(hingeAt(i)[1])),
      mode: "markers", name: `hinge, ${status}`,
      text: which.map((i) => body.hinges[i]), hovertemplate: "%{text}<extra></extra>",
      marker: looks[status],
    });
  }
  const win = shapeWindow(c);
  const unit = label("length");
  draw("wing-shape-plot", traces, `The wing at t = ${sig(t, 4)} s, ${wingTemperature(c)}`,
    `x, away from the spacecraft [${unit}]`, `y [${unit}]`, {
      xaxis: { title: { text: `x, away from the spacecraft [${unit}]` }, range: win.x, zeroline: false },
      yaxis: { title: { text: `y [${unit}]` }, range: win.y, scaleanchor: "x", scaleratio: 1, zeroline: false },
      shapes: [{ type: "rect", xref: "x", yref: "paper", x0: -win.wall, x1: 0, y0: 0, y1: 1,
        fillcolor: "#cfd8dc", line: { color: "#90a4ae", width: 1 }, layer: "below" }],
      annotations: [{ x: -win.wall / 2, y: 0.5, xref: "x", yref: "paper", text: "spacecraft", textangle: -90,
        showarrow: false, font: { size: 11, color: "#37474f" } }],
    });
  const status = body.hinges.map((h) => `${h} ${hingeStatus(h, done, stuck)}`).join(", ");
  const angles = body.hinges.map((h, j) => `${h} ${sig(deg(c.angle_rad[j][k]), 4)} deg`).join(", ");
  document.getElementById("wing-state").textContent = `t = ${sig(t, 4)} s: ${status}. Deployed angles: ${angles}.`;
  const slider = document.getElementById("wing-time");
  slider.value = String(Math.round((wingView.time / endTime(c)) * TIME_STEPS));
  const text = `t = ${sig(t, 4)} s (sample ${k + 1} of ${c.time_s.length})`;
  slider.setAttribute("aria-valuetext", text);
  document.getElementById("wing-time-value").textContent = text;
  document.getElementById("wing-shape-plot").dataset.frame = String(k);
}

function endTime(c) { return c.time_s[c.time_s.length - 1] || 1; }

// The last of the case's samples at or before time t.
function frameAt(c, t) {
  let lo = 0, hi = c.time_s.length - 1;
  if (t >= c.time_s[hi]) return hi;
  while (lo < hi) { // the largest k with time_s[k] <= t
    const mid = Math.ceil((lo + hi) / 2);
    if (c.time_s[mid] <= t) lo = mid; else hi = mid - 1;
  }
  return lo;
}

// Move the animation to time t (the slider, play): the wing and the angle plot's cursor.
function showTime(t) {
  const c = wingCase();
  wingView.time = Math.max(0, Math.min(endTime(c), t));
  wingView.frame = frameAt(c, wingView.time);
  drawWingShape();
  Plotly.relayout("wing-angle-plot", { shapes: cursorShape() });
}

// ---------------------------------------------------------------- play and pause

function pauseWing() {
  wingView.playing = false;
  wingView.lastTick = null;
  const button = document.getElementById("wing-play");
  button.textContent = "Play";
  button.setAttribute("aria-pressed", "false");
}

function tick(now) {
  if (!wingView.playing || !state.wing) return;
  const end = endTime(wingCase());
  const step = wingView.lastTick === null ? 0 : ((now - wingView.lastTick) / 1000) * (end / PLAY_SECONDS);
  wingView.lastTick = now;
  showTime(wingView.time + step);
  if (wingView.time >= end) { pauseWing(); return; }
  requestAnimationFrame(tick);
}

function togglePlay() {
  if (!state.wing) return;
  if (wingView.playing) { pauseWing(); return; }
  if (wingView.time >= endTime(wingCase())) wingView.time = 0; // at the end: from the start
  wingView.playing = true;
  wingView.lastTick = null;
  const button = document.getElementById("wing-play");
  button.textContent = "Pause";
  button.setAttribute("aria-pressed", "true");
  showTime(wingView.time);
  requestAnimationFrame(tick);
}

// ---------------------------------------------------------------- table and controls

function latchLoad(l) {
  if (l.peak_torque_Nm !== null && l.peak_torque_Nm !== undefined) return `peak ${sig(show("torque", l.peak_torque_Nm), 4)} ${label("torque")}`;
  if (l.impulse_Nms !== null && l.impulse_Nms !== undefined) return `impulse ${sig(Math.abs(show("torque", l.impulse_Nms)), 4)} ${label("torque")}*s`;
  return "rigid latch (with its group)";
}

function renderWingTable() {
  const body = state.wing;
  const table = document.getElementById("wing-table");
  const heads = [`temperature [${label("temperature")}]`, "deployed in [s]", "hinge", "latches at [s]",
    `speed [${label("angular_speed")}]`, `kinetic energy of the wing [${label("energy")}]`, "latch load"];
  table.querySelector("thead").innerHTML = `<tr>${heads.map((h) => `<th scope="col">${escapeHtml(h)}</th>`).join("")}</tr>`;
  const rows = [];
  body.result.cases.forEach((r, i) => {
    const c = body.cases[i];
    const lines = r.latches.map((l) => [escapeHtml(l.hinge), sig(l.time_s, 5), sig(show("angular_speed", l.speed_rad_s), 4),
      sig(show("energy", l.kinetic_energy_J), 4), escapeHtml(latchLoad(l))]);
    for (const h of r.stuck_hinges) {
      const j = body.hinges.indexOf(h);
      lines.push([escapeHtml(h), `stuck at ${sig(deg(c.angle_rad[j][c.angle_rad[j].length - 1]), 4)} deg`, "-", "-", "-"]);
    }
    if (!lines.length) lines.push(["-", "-", "-", "-", "-"]);
    const deployed = r.deployment_time_s === null ? `not deployed (${escapeHtml(r.status)})` : sig(r.deployment_time_s, 5);
    lines.forEach((cells, n) => {
      const lead = n === 0
        ? `<th scope="row" rowspan="${lines.length}" class="group">${escapeHtml(wingTemperature(c))}</th>` +
          `<td rowspan="${lines.length}" class="num${r.deployment_time_s === null ? " stalled" : ""}">${deployed}</td>`
        : "";
      const rest = cells.map((v, m) => `<td class="${m === 0 || m === 4 ? "" : "num"}${String(v).startsWith("stuck") ? " stalled" : ""}">${v}</td>`).join("");
      rows.push(`<tr>${lead}${rest}</tr>`);
    });
  });
  table.querySelector("tbody").innerHTML = rows.join("");
}

function buildWingControls() {
  const select = document.getElementById("wing-temperature");
  const previous = state.wing.cases.findIndex((c) => String(c.temperature_C) === select.value);
  select.innerHTML = state.wing.cases.map((c, i) => `<option value="${c.temperature_C}">${escapeHtml(wingTemperature(c))}</option>`).join("");
  wingView.caseIndex = previous >= 0 ? previous : 0;
  select.selectedIndex = wingView.caseIndex;
  const c = wingCase();
  const slider = document.getElementById("wing-time");
  slider.max = String(TIME_STEPS);
  wingView.time = Math.min(wingView.time, endTime(c));
  wingView.frame = frameAt(c, wingView.time);
  // The latches as the slider's tick marks.
  const ticks = wingResultCase().latches.map((l) => Math.round((l.time_s / endTime(c)) * TIME_STEPS));
  document.getElementById("wing-latch-ticks").innerHTML = ticks.map((k) => `<option value="${k}"></option>`).join("");
}

// A new answer from POST /api/wing (state.wing): draw everything.
function renderWing() {
  buildWingControls();
  drawWingAngles();
  drawWingShape();
  renderWingTable();
  document.getElementById("timing").textContent = `Last computation ${sig(state.wing.compute_ms, 3)} ms on the server.`;
}

document.getElementById("wing-time").addEventListener("input", (e) => {
  if (wingView.playing) pauseWing();
  showTime((Number(e.target.value) / TIME_STEPS) * endTime(wingCase()));
});
document.getElementById("wing-play").addEventListener("click", togglePlay);
document.getElementById("wing-temperature").addEventListener("change", (e) => {
  pauseWing();
  wingView.caseIndex = e.target.selectedIndex;
  wingView.time = 0;
  renderWing();
});
