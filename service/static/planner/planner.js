// wearcast planner page: plain JavaScript against the /v1 API, no build step.
// Fleet table (sortable, filterable, coloured by urgency), a wheel's Sd/Sh/qR history and
// forecast with the limits, its latest profile over its targets, and the lathe plan by week.
"use strict";

const API = "../v1";
const state = { wheels: [], sort: { key: "p10", dir: 1 }, fleetId: "", today: "" };

const $ = (id) => document.getElementById(id);
const fmt = (v, digits = 2) =>
  v === null || v === undefined ? "–" : (typeof v === "number" ? v.toFixed(digits) : String(v));
const km = (v) => (v === null || v === undefined ? "–" : v === "inf" ? "∞" :
  Math.round(v).toLocaleString("en-US"));
const num = (v) => (v === "inf" ? Infinity : v === null || v === undefined ? NaN : Number(v));

// The API needs a key (Authorization: Bearer <key>). The page asks for it once and keeps it
// in this tab's sessionStorage; a link may carry it in the fragment (#key=...), which the
// browser never sends to the server.
const KEY_STORE = "wearcast-api-key";

function apiKey() {
  return sessionStorage.getItem(KEY_STORE) || "";
}

function authHeaders(extra = {}) {
  const key = apiKey();
  return key ? { ...extra, Authorization: `Bearer ${key}` } : extra;
}

async function api(path, options = {}) {
  const response = await fetch(API + path,
    { ...options, headers: authHeaders(options.headers || {}) });
  if (response.status === 401) {
    $("api-key").focus();
    throw new Error("401: enter an API key with the read scope (write to create plans)");
  }
  const text = await response.text();
  if (!response.ok) throw new Error(`${response.status}: ${text}`);
  return JSON.parse(text);
}

function params(extra = {}) {
  const p = new URLSearchParams();
  if (state.fleetId) p.set("fleet_id", state.fleetId);
  if (state.today) p.set("today", state.today);
  for (const [k, v] of Object.entries(extra)) p.set(k, v);
  const s = p.toString();
  return s ? "?" + s : "";
}

function status(text, error = false) {
  $("status").textContent = text;
  $("status").className = error ? "error" : "";
}

// ---------------------------------------------------------------- fleet table

function row(w) {
  const gov = w.first_limit.governing_p10;
  return {
    wheel_id: w.wheel_id, vehicle_id: w.vehicle_id,
    position: `${w.bogie_type} ${w.axle} ${w.side}`, mileage_km: w.mileage_km,
    measured_on: w.measured_on, sd_mm: w.sd_mm, sh_mm: w.sh_mm, qr_mm: w.qr_mm,
    diameter_mm: w.diameter_mm, p10: w.first_limit.p10, p50: w.first_limit.p50,
    governing: gov, date_p10: gov ? w.dates[gov].p10 : null, urgency: w.urgency,
  };
}

const URGENCY_ORDER = { crossed: 0, due: 1, soon: 2, ok: 3, unknown: 4 };

function compare(a, b, key) {
  let x = a[key], y = b[key];
  if (key === "urgency") { x = URGENCY_ORDER[x]; y = URGENCY_ORDER[y]; }
  if (["p10", "p50"].includes(key)) { x = num(x); y = num(y); }
  const missing = (v) => v === null || v === undefined || (typeof v === "number" && isNaN(v));
  if (missing(x) && missing(y)) return 0;
  if (missing(x)) return 1;
  if (missing(y)) return -1;
  return x < y ? -1 : x > y ? 1 : 0;
}

function renderFleet() {
  const text = $("filter").value.trim().toLowerCase();
  const urgency = $("urgency-filter").value;
  const { key, dir } = state.sort;
  const rows = state.wheels.map(row)
    .filter((r) => !text || r.wheel_id.toLowerCase().includes(text) ||
      r.vehicle_id.toLowerCase().includes(text))
    .filter((r) => !urgency || r.urgency === urgency)
    .sort((a, b) => {
      const c = compare(a, b, key);
      return c !== 0 ? dir * c : compare(a, b, "wheel_id");
    });
  const body = $("fleet-table").tBodies[0];
  body.replaceChildren(...rows.map((r) => {
    const tr = document.createElement("tr");
    tr.className = "u-" + r.urgency;
    tr.dataset.wheelId = r.wheel_id;
    const cells = [
      ["wheel_id", r.wheel_id], ["vehicle_id", r.vehicle_id], ["position", r.position],
      ["mileage_km", km(r.mileage_km)], ["measured_on", r.measured_on || "–"],
      ["sd_mm", fmt(r.sd_mm)], ["sh_mm", fmt(r.sh_mm)], ["qr_mm", fmt(r.qr_mm)],
      ["diameter_mm", fmt(r.diameter_mm, 1)], ["p10", km(r.p10)], ["p50", km(r.p50)],
      ["governing", r.governing || "–"], ["date_p10", r.date_p10 || "–"],
      ["urgency", r.urgency]];
    for (const [col, value] of cells) {
      const td = document.createElement("td");
      td.dataset.col = col;
      td.textContent = value;
      tr.append(td);
    }
    tr.addEventListener("click", () => openWheel(r.wheel_id));
    return tr;
  }));
  $("fleet-count").textContent = `(${rows.length} of ${state.wheels.length} wheels)`;
  for (const th of document.querySelectorAll("#fleet-table th")) {
    th.classList.toggle("asc", th.dataset.sort === key && dir === 1);
    th.classList.toggle("desc", th.dataset.sort === key && dir === -1);
  }
}

function renderSpreads(spreads) {
  const box = $("spreads");
  box.replaceChildren();
  if (!spreads.length) return;
  const p = document.createElement("p");
  p.className = "error";
  p.textContent = "Diameter differences over the limit: " + spreads.map((s) =>
    `${s.scope} ${s.key} ${s.spread_mm.toFixed(2)} mm > ${s.limit_mm} mm`).join("; ");
  box.append(p);
}

async function loadFleet() {
  state.fleetId = $("fleet-id").value.trim();
  state.today = $("today").value;
  status("loading…");
  try {
    const data = await api("/fleet/state" + params());
    state.wheels = data.wheels;
    renderFleet();
    renderSpreads(data.diameter_spreads);
    status(`${data.n_wheels} wheels, today ${data.today}`);
  } catch (e) {
    status(e.message, true);
  }
  loadPlanList();
}

// ---------------------------------------------------------------- charts (SVG)

const SVG = "http://www.w3.org/2000/svg";

function el(name, attrs, parent) {
  const node = document.createElementNS(SVG, name);
  for (const [k, v] of Object.entries(attrs)) node.setAttribute(k, v);
  if (parent) parent.append(node);
  return node;
}

function frame(svg, xs, ys) {
  svg.replaceChildren();
  const W = 420, H = 240, L = 48, R = 10, T = 10, B = 28;
  svg.setAttribute("viewBox", `0 0 ${W} ${H}`);
  const finite = (a) => a.filter((v) => Number.isFinite(v));
  let [x0, x1] = [Math.min(...finite(xs)), Math.max(...finite(xs))];
  let [y0, y1] = [Math.min(...finite(ys)), Math.max(...finite(ys))];
  if (x0 === x1) { x0 -= 1; x1 += 1; }
  if (y0 === y1) { y0 -= 1; y1 += 1; }
  const pad = (y1 - y0) * 0.08; y0 -= pad; y1 += pad;
  const sx = (x) => L + (x - x0) / (x1 - x0) * (W - L - R);
  const sy = (y) => H - B - (y - y0) / (y1 - y0) * (H - T - B);
  el("line", { x1: L, y1: H - B, x2: W - R, y2: H - B, class: "axis" }, svg);
  el("line", { x1: L, y1: T, x2: L, y2: H - B, class: "axis" }, svg);
  for (let i = 0; i <= 4; i++) {
    const xv = x0 + (x1 - x0) * i / 4, yv = y0 + (y1 - y0) * i / 4;
    el("text", { x: sx(xv), y: H - 10, "text-anchor": "middle" }, svg).textContent =
      Math.abs(x1 - x0) > 1000 ? Math.round(xv / 1000) + "k" : xv.toFixed(0);
    el("text", { x: L - 4, y: sy(yv) + 3, "text-anchor": "end" }, svg).textContent =
      yv.toFixed(1);
  }
  return { sx, sy, x0, x1 };
}

function parameterChart(svg, name, history, forecast, limit) {
  const pts = history.filter((h) => h[name + "_mm"] !== null);
  const xs = pts.map((h) => h.mileage_km), ys = pts.map((h) => h[name + "_mm"]);
  const lines = forecast ? forecast.lines : {};
  for (const q of Object.values(lines)) for (const [x, y] of q) { xs.push(x); ys.push(y); }
  ys.push(limit);
  if (!xs.length) { svg.replaceChildren(); return; }
  const f = frame(svg, xs, ys);
  el("line", { x1: f.sx(f.x0), x2: f.sx(f.x1), y1: f.sy(limit), y2: f.sy(limit),
               class: "limit", "data-limit": limit }, svg);
  for (const [q, line] of Object.entries(lines)) {
    el("polyline", { points: line.map(([x, y]) => `${f.sx(x)},${f.sy(y)}`).join(" "),
                     class: q, fill: "none", "data-quantile": q }, svg);
  }
  for (const h of pts) {
    el("circle", { cx: f.sx(h.mileage_km), cy: f.sy(h[name + "_mm"]), r: 3, class: "point",
                   "data-mileage": h.mileage_km, "data-value": h[name + "_mm"] }, svg);
  }
}

function profileChart(svg, profile) {
  if (!profile) { svg.replaceChildren(); return; }
  const ref = profile.reference;
  const names = Object.keys(ref).filter((k) => k !== "y_mm");
  const xs = [...profile.y_mm, ...ref.y_mm];
  const ys = [...profile.z_mm, ...ref.S1002].filter((v) => v !== null);
  const f = frame(svg, xs, ys);
  const path = (y, z) => y.map((v, i) => (z[i] === null ? null : `${f.sx(v)},${f.sy(z[i])}`))
    .filter((p) => p).join(" ");
  for (const name of names) {
    el("polyline", { points: path(ref.y_mm, ref[name]),
                     class: name === "S1002" ? "reference" : "variant",
                     "data-target": name }, svg);
  }
  el("polyline", { points: path(profile.y_mm, profile.z_mm), class: "measured",
                   "data-points": profile.y_mm.length }, svg);
}

// ---------------------------------------------------------------- one wheel

async function openWheel(wheelId) {
  status("loading " + wheelId + "…");
  try {
    const d = await api(`/fleet/wheels/${encodeURIComponent(wheelId)}` + params());
    const w = d.wheel;
    $("wheel-panel").hidden = false;
    $("wheel-title").textContent = `Wheel ${w.wheel_id}`;
    $("wheel-summary").textContent =
      `${w.vehicle_id}, ${w.bogie_type} bogie, axle ${w.axle}, ${w.side}; ` +
      `${w.n_since_turning} measurements since turning; first limit ` +
      `${w.first_limit.governing_p10 || "–"} in ${km(w.first_limit.p10)} km (P10), ` +
      `${km(w.first_limit.p50)} km (P50); ${w.km_per_day ? w.km_per_day.toFixed(0) : "–"} ` +
      `km/day (${w.km_per_day_source})`;
    const lim = d.limits;
    parameterChart($("chart-sd"), "sd", d.history, d.forecast.sd, lim.sd_min_mm);
    parameterChart($("chart-sh"), "sh", d.history, d.forecast.sh, lim.sh_max_mm);
    parameterChart($("chart-qr"), "qr", d.history, d.forecast.qr, lim.qr_min_mm);
    profileChart($("chart-profile"), d.profile);
    const body = $("turning-table").tBodies[0];
    body.replaceChildren();
    const t = d.turning;
    if (t && t.options) {
      for (const o of t.options) {
        const tr = document.createElement("tr");
        tr.dataset.target = o.target;
        const choice = [o.target === t.economic ? "most km/mm" : "",
                        o.target === t.least_loss ? "least loss" : ""].filter((s) => s);
        for (const v of [o.target, fmt(o.diameter_loss_mm), km(o.km_to_next_limit),
                         km(o.km_per_mm), choice.join(", ")]) {
          const td = document.createElement("td");
          td.textContent = v;
          tr.append(td);
        }
        body.append(tr);
      }
      $("wheel-life").textContent = t.life ?
        `${t.life.turnings_left} turnings left to the scrap diameter, ` +
        `${km(t.life.km_to_scrap)} km` : "";
    } else {
      $("wheel-life").textContent = t && t.error ? t.error : "no measured profile";
    }
    status(`wheel ${wheelId}`);
  } catch (e) {
    status(e.message, true);
  }
}

// ---------------------------------------------------------------- plan

function cell(tr, text) {
  const td = document.createElement("td");
  td.textContent = text;
  tr.append(td);
  return td;
}

function renderPlan(plan) {
  $("plan-result").hidden = false;
  const c = plan.cost;
  $("plan-summary").textContent =
    `Plan ${plan.id}: ${plan.wheelsets.filter((w) => w.week !== null).length} wheelsets ` +
    `turned in ${plan.horizon_weeks} weeks from ${plan.start}, ` +
    `${plan.capacity_per_week} a week. Diameter per 1,000 km: plan ` +
    `${fmt(c.plan.mm_per_1000km, 3)} mm, fixed ${km(c.fixed_interval_km)} km ` +
    `${fmt(c.fixed_mileage.mm_per_1000km, 3)} mm; km new to scrap: plan ` +
    `${km(c.plan.km_new_to_scrap)}, fixed ${km(c.fixed_mileage.km_new_to_scrap)}.`;
  const exp = $("plan-export");
  exp.replaceChildren();
  for (const f of ["json", "csv"]) {
    const a = document.createElement("a");
    a.href = `${API}/plans/${plan.id}?format=${f}`;
    a.textContent = `export ${f.toUpperCase()}`;
    a.id = `plan-export-${f}`;
    a.addEventListener("click", (e) => { e.preventDefault(); download(a.href, plan.id, f); });
    exp.append(a, " ");
  }
  const risk = $("plan-at-risk");
  risk.textContent = plan.at_risk.length ?
    "At risk: " + plan.at_risk.map((r) => `${r.wheelset} (${r.reason})`).join("; ") : "";
  const weeks = $("plan-weeks").tBodies[0];
  weeks.replaceChildren(...plan.weeks.filter((w) => w.load > 0).map((w) => {
    const tr = document.createElement("tr");
    tr.dataset.week = w.week;
    cell(tr, w.week); cell(tr, w.starts_on); cell(tr, w.load);
    cell(tr, w.wheelsets.join(", ")).dataset.col = "wheelsets";
    return tr;
  }));
  const sets = $("plan-wheelsets").tBodies[0];
  sets.replaceChildren(...plan.wheelsets.filter((w) => w.week !== null || w.at_risk)
    .map((w) => {
      const tr = document.createElement("tr");
      tr.dataset.wheelset = w.wheelset;
      tr.className = w.at_risk ? "u-crossed" : "";
      cell(tr, w.wheelset); cell(tr, w.week ?? "–"); cell(tr, w.turn_date || "–");
      cell(tr, w.deadline || "–"); cell(tr, w.action);
      cell(tr, Object.entries(w.cuts).map(([id, c]) =>
        `${id}: ${c.target || "–"} ${fmt(c.diameter_loss_mm)} mm`).join("; "));
      cell(tr, w.in_time ? "yes" : "no");
      cell(tr, w.reason).dataset.col = "reason";  // e.g. a companion turning for the bogie
      return tr;
    }));
}

async function runPlan(event) {
  event.preventDefault();
  const body = {
    horizon_weeks: Number($("plan-weeks-n").value),
    capacity_per_week: Number($("plan-capacity").value),
    fixed_interval_km: Number($("plan-fixed").value),
  };
  if (state.fleetId) body.fleet_id = state.fleetId;
  const start = $("plan-start").value || state.today;
  if (start) body.start = start;
  status("planning…");
  try {
    const plan = await api("/plans", { method: "POST", body: JSON.stringify(body),
                                       headers: { "Content-Type": "application/json" } });
    renderPlan(plan);
    status(`plan ${plan.id}`);
    loadPlanList();
  } catch (e) {
    status(e.message, true);
  }
}

async function loadPlanList() {
  try {
    const plans = await api("/plans");
    const select = $("plan-list");
    select.replaceChildren(new Option("stored plans…", ""),
      ...plans.map((p) => new Option(`plan ${p.id} (${p.fleet_id || "all"})`, p.id)));
  } catch (e) { /* the list is a convenience */ }
}

async function download(url, id, format) {
  // a plain link cannot send the API key: fetch with it and save the answer as a file
  try {
    const response = await fetch(url, { headers: authHeaders() });
    if (!response.ok) throw new Error(`${response.status}: ${await response.text()}`);
    const link = document.createElement("a");
    link.href = URL.createObjectURL(await response.blob());
    link.download = `plan-${id}.${format}`;
    link.click();
    URL.revokeObjectURL(link.href);
  } catch (e) { status(e.message, true); }
}

async function openPlan() {
  const id = $("plan-list").value;
  if (!id) return;
  try { renderPlan(await api(`/plans/${id}`)); } catch (e) { status(e.message, true); }
}

// ---------------------------------------------------------------- wiring

function init() {
  const fragment = new URLSearchParams(location.hash.slice(1));
  if (fragment.get("key")) {
    sessionStorage.setItem(KEY_STORE, fragment.get("key"));
    history.replaceState(null, "", location.pathname + location.search);
  }
  $("api-key").value = apiKey();
  $("api-key").addEventListener("change", () => {
    sessionStorage.setItem(KEY_STORE, $("api-key").value.trim());
    loadFleet();
  });
  const q = new URLSearchParams(location.search);
  $("fleet-id").value = q.get("fleet_id") || "";
  $("today").value = q.get("today") || "";
  $("scope").addEventListener("submit", (e) => { e.preventDefault(); loadFleet(); });
  $("filter").addEventListener("input", renderFleet);
  $("urgency-filter").addEventListener("change", renderFleet);
  for (const th of document.querySelectorAll("#fleet-table th")) {
    th.addEventListener("click", () => {
      const key = th.dataset.sort;
      state.sort = { key, dir: state.sort.key === key ? -state.sort.dir : 1 };
      renderFleet();
    });
  }
  $("plan-form").addEventListener("submit", runPlan);
  $("plan-list").addEventListener("change", openPlan);
  loadFleet();
}

document.addEventListener("DOMContentLoaded", init);
