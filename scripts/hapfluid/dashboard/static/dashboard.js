// The operator's page: shows what haptic-dashboard sends over /ws and sends nothing back.
"use strict";

const HISTORY_S = 10;
const COLORS = { sent: "#1f77b4", hand: "#2ca02c", sim: "#ff7f0e" };
let snapshot = null;
let history = [];
let drawPending = false;

const $ = (id) => document.getElementById(id);
const norm = (v) => Math.hypot(v[0], v[1], v[2]);
const fmt = (x, digits = 3) => (x === undefined || x === null || !isFinite(x) ? "-" : Number(x).toFixed(digits));
const vec = (v, digits = 3) => `[${v.map((x) => fmt(x, digits)).join(", ")}]`;

function setStatus(el, text, good, warnOnly) {
  el.textContent = text;
  el.classList.remove("ok", "warn", "bad");
  el.classList.add("status", good ? "ok" : warnOnly ? "warn" : "bad");
}

function deviceCard(i, name) {
  let card = document.querySelector(`.device[data-index="${i}"]`);
  if (!card) {
    card = $("device-template").content.firstElementChild.cloneNode(true);
    card.dataset.index = i;
    $("devices").appendChild(card);
  }
  card.dataset.name = name;
  return card;
}

function waitingFor(s) {
  const parts = [];
  if (s.observer !== "live") return [`the observer: ${s.observer}`];
  if (s.loop.status !== "live") parts.push(`haptic-rt (its trace: ${s.loop.status})`);
  if (s.sim.status !== "live") parts.push(`haptic-sim (its samples: ${s.sim.status})`);
  return parts;
}

function render() {
  drawPending = false;
  const s = snapshot;
  if (!s) return;
  $("prefix").textContent = s.prefix ? `(${s.prefix})` : "";
  const waiting = waitingFor(s);
  $("banner").hidden = waiting.length === 0;
  $("banner").textContent = waiting.length ? "waiting for " + waiting.join(", ") : "";
  if (s.observer !== "live") return;

  setStatus($("loop-status"), s.loop.status, s.loop.status === "live");
  const lat = s.loop.wake_latency_us;
  $("loop-latency").textContent = `${fmt(lat.p50, 0)} / ${fmt(lat.p99, 0)} / ${fmt(lat["p99.9"], 0)} µs`;
  $("loop-max").textContent = `${fmt(lat.max, 1)} µs over ${lat.n} ticks`;
  $("loop-overruns").textContent = s.loop.overruns;
  $("loop-misses").textContent = s.loop.deadline_misses;
  $("loop-ticks").textContent = s.loop.tick + (s.loop.degraded ? " (degraded: no real-time rights)" : "");
  drawHistogram($("latency-histogram"), lat.histogram);

  setStatus($("sim-status"), s.sim.status, s.sim.status === "live");
  $("sim-backend").textContent = s.sim.backend
    ? s.sim.backend + (s.sim.threads_active ? `, ${s.sim.threads_active} thread(s)` : "") : "-";
  $("sim-rate").textContent = fmt(s.sim.steps_per_s, 1);
  const rtf = $("sim-rtf");
  rtf.textContent = fmt(s.sim.real_time_factor, 2);
  rtf.className = s.sim.real_time_factor >= 0.98 ? "ok" : "warn";
  $("sim-particles").textContent = s.sim.fluid_particles || "-";
  $("sim-age").textContent = s.sim.sample_age_ms >= 0 ? `${fmt(s.sim.sample_age_ms, 1)} ms` : "-";

  s.devices.forEach((d, i) => {
    const card = deviceCard(i, d.name);
    card.querySelector(".name").textContent = d.name || `device ${i}`;
    setStatus(card.querySelector(".link"), d.link_ok ? "linked" : "link fault", d.link_ok);
    card.querySelector(".quality").textContent =
      `${fmt(100 * d.fresh_share, 1)} % fresh` + (d.miss_run ? `, ${d.miss_run} ticks missed now` : "");
    const faults = card.querySelector(".faults");
    faults.textContent = d.faults || "none";
    faults.className = "faults " + (d.faults ? "bad" : "ok");
    card.querySelector(".last-fault").textContent =
      d.last_fault ? `${d.last_fault} (${fmt(d.last_fault_age_s, 1)} s ago)` : "none";
    card.querySelector(".engage").textContent = d.engage;
    card.querySelector(".estop").textContent = d.estop ? "LATCHED" : "clear";
    card.querySelector(".estop").className = "estop " + (d.estop ? "bad" : "ok");
    card.querySelector(".deadman").textContent = d.deadman ? "pressed" : "released";
    card.querySelector(".flags").textContent = d.flags || "none";
    const f = card.querySelector(".force-now");
    f.textContent = `${vec(d.command_force_n)} N, |F| ${fmt(norm(d.command_force_n))} N`;
    f.dataset.fx = d.command_force_n[0];
    f.dataset.fy = d.command_force_n[1];
    f.dataset.fz = d.command_force_n[2];
    f.dataset.tick = s.loop.tick;
    card.querySelector(".position").textContent = `${vec(d.position_m, 4)} m`;
    drawSeries(card.querySelector(".force-plot"), i, "force_n");
    drawSeries(card.querySelector(".torque-plot"), i, "torque_nm");
  });

  const list = $("flight");
  const dumps = s.flight_dumps || [];
  list.replaceChildren(...(dumps.length ? dumps.map((f) => {
    const li = document.createElement("li");
    const a = document.createElement("a");
    a.href = "/flight/" + encodeURIComponent(f.name);
    a.textContent = f.name;
    li.append(a, ` (${(f.bytes / 1024).toFixed(1)} KiB, ${fmt(f.age_s, 0)} s ago)`);
    return li;
  }) : [Object.assign(document.createElement("li"), { textContent: "none yet", className: "none" })]));
}

function drawSeries(canvas, device, what) {
  const ctx = canvas.getContext("2d");
  const w = canvas.width, h = canvas.height;
  ctx.clearRect(0, 0, w, h);
  const pts = history.filter((p) => p.devices[device]);
  canvas.dataset.points = pts.length;
  if (pts.length < 2) return;
  const tEnd = pts[pts.length - 1].t, tStart = tEnd - HISTORY_S;
  const series = {
    sent: pts.map((p) => norm(p.devices[device]["command_" + what])),
    hand: pts.map((p) => norm(p.devices[device]["hand_" + what])),
    sim: pts.map((p) => (p.devices[device].sim_valid ? norm(p.devices[device]["sim_" + what]) : NaN)),
  };
  let top = 0;
  for (const k in series) for (const v of series[k]) if (isFinite(v)) top = Math.max(top, v);
  top = top > 0 ? top * 1.15 : 1;
  ctx.fillStyle = "#5f6368";
  ctx.font = "11px sans-serif";
  ctx.fillText(fmt(top, top < 0.1 ? 3 : 2), 2, 11);
  ctx.fillText("0", 2, h - 2);
  for (const k of ["sim", "hand", "sent"]) {
    ctx.strokeStyle = COLORS[k];
    ctx.lineWidth = k === "sent" ? 2 : 1.5;
    ctx.beginPath();
    let pen = false;
    pts.forEach((p, j) => {
      const v = series[k][j];
      if (!isFinite(v)) { pen = false; return; }
      const x = ((p.t - tStart) / HISTORY_S) * w, y = h - (v / top) * (h - 4) - 2;
      if (pen) ctx.lineTo(x, y); else ctx.moveTo(x, y);
      pen = true;
    });
    ctx.stroke();
  }
}

function drawHistogram(canvas, bins) {
  const ctx = canvas.getContext("2d");
  const w = canvas.width, h = canvas.height;
  ctx.clearRect(0, 0, w, h);
  if (!bins || !bins.length) return;
  const logMax = Math.log10(1 + Math.max(...bins));
  const bw = w / bins.length;
  bins.forEach((c, i) => {
    const bh = logMax > 0 ? (Math.log10(1 + c) / logMax) * (h - 14) : 0;
    ctx.fillStyle = i === bins.length - 1 ? "#d62728" : "#1f77b4";
    ctx.fillRect(i * bw + 1, h - 12 - bh, bw - 2, bh);
  });
  ctx.fillStyle = "#5f6368";
  ctx.font = "10px sans-serif";
  ctx.fillText("0", 0, h - 1);
  ctx.fillText("100 µs", w / 2 - 14, h - 1);
  ctx.fillText("200+", w - 26, h - 1);
}

function schedule() {
  if (!drawPending) {
    drawPending = true;
    requestAnimationFrame(render);
  }
}

function connect() {
  const ws = new WebSocket((location.protocol === "https:" ? "wss://" : "ws://") + location.host + "/ws");
  ws.onopen = () => setStatus($("connection"), "connected", true);
  ws.onclose = () => {
    setStatus($("connection"), "disconnected: retrying", false);
    setTimeout(connect, 1000);
  };
  ws.onmessage = (event) => {
    const m = JSON.parse(event.data);
    if (m.history) history = m.history;
    if (m.point) {
      history.push(m.point);
      const tEnd = m.point.t;
      while (history.length && tEnd - history[0].t > HISTORY_S) history.shift();
    }
    snapshot = m.snapshot;
    schedule();
  };
}

connect();
