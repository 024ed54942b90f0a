// tmpnav serve's live view: the site, one plan's paths, beliefs and schedule, and its revisions
// as the service pushes them (server-sent events). Plain canvas drawing, no library.
"use strict";

const params = new URLSearchParams(location.search);
const token = params.get("token");
// the robots' colours in the order plan.png and schedule.png give them (tmpnav.report.figures.ROBOT_COLORS)
const COLOURS = ["#1f77b4", "#2ca02c", "#d62728", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf"];
// the line of each round of COLOURS (canvas dash arrays, px): solid, dashed, dotted, dash-dotted
const DASHES = [[], [8, 4], [2, 3], [8, 4, 2, 4]];
const view = { site: null, map: null, plan: null, planId: params.get("plan"), revision: -1, t: 0 };

function withToken(path) {
  return token ? path + (path.includes("?") ? "&" : "?") + "token=" + encodeURIComponent(token) : path;
}

async function get(path) {
  const answer = await fetch(withToken(path), { cache: "no-store" });
  if (!answer.ok) throw new Error(path + ": " + answer.status);
  return answer.json();
}

// the map frame (m, y up) onto a canvas, the site's bounds fitted with a margin
function frame(canvas) {
  const [x0, y0, x1, y1] = view.site.bounds;
  const pad = 10, s = Math.min((canvas.width - 2 * pad) / (x1 - x0), (canvas.height - 2 * pad) / (y1 - y0));
  return { s, px: (x) => pad + (x - x0) * s, py: (y) => pad + (y1 - y) * s };
}

// robot k of the site's list (0-based): colour COLOURS[k % 8], line DASHES[k // 8], so that the
// robots of a fleet that share a colour are told apart by their line (as in plan.png)
function robotStyle(index) {
  const round = Math.floor(index / COLOURS.length) % DASHES.length;
  return { colour: COLOURS[index % COLOURS.length], dash: DASHES[round] };
}

function styleOf(robot) {
  const names = view.site.robots.map((r) => r.name);
  return robotStyle(Math.max(0, names.indexOf(robot)));
}

// a line of the robot's dash after its dot in the list, for the robots past the eighth
function dashSwatch(style) {
  const ns = "http://www.w3.org/2000/svg";
  const svg = document.createElementNS(ns, "svg"), line = document.createElementNS(ns, "line");
  svg.setAttribute("width", "26");
  svg.setAttribute("height", "8");
  svg.style.verticalAlign = "middle";
  svg.style.marginRight = "4px";
  const attributes = {
    x1: 0, y1: 4, x2: 26, y2: 4, stroke: style.colour, "stroke-width": 2, "stroke-dasharray": style.dash.join(" "),
  };
  for (const [name, value] of Object.entries(attributes)) line.setAttribute(name, String(value));
  svg.appendChild(line);
  return svg;
}

// the belief of a robot at time t: its trajectory's step at or before t (docs/plan-json.md)
function beliefAt(robot, t) {
  const steps = view.plan.trajectories[robot] || [];
  if (!steps.length) return null;
  const i = Math.max(0, Math.min(steps.length - 1, Math.floor(t / view.plan.dt + 1e-9)));
  return steps[i];
}

// the 2-sigma ellipse of a position covariance: half-axes and the angle of the first
function ellipse(cov) {
  const a = cov[0][0], b = cov[0][1], d = cov[1][1];
  const mid = (a + d) / 2, rad = Math.sqrt(((a - d) / 2) ** 2 + b * b);
  const l1 = Math.max(mid + rad, 0), l2 = Math.max(mid - rad, 0);
  return { rx: 2 * Math.sqrt(l1), ry: 2 * Math.sqrt(l2), angle: Math.atan2(l1 - a, b || 1e-12) };
}

function drawEllipse(g, f, x, y, cov, style, fill) {
  const e = ellipse(cov);
  g.beginPath();
  g.ellipse(f.px(x), f.py(y), Math.max(e.rx * f.s, 1), Math.max(e.ry * f.s, 1), -e.angle, 0, 2 * Math.PI);
  g.strokeStyle = style.colour;
  g.lineWidth = 1;
  g.setLineDash(style.dash);
  g.stroke();
  g.setLineDash([]);
  if (fill) { g.fillStyle = fill; g.fill(); }
}

function drawSite(g, f) {
  const [x0, y0, x1, y1] = view.site.bounds;
  if (view.map && view.map.complete) g.drawImage(view.map, f.px(x0), f.py(y1), (x1 - x0) * f.s, (y1 - y0) * f.s);
  g.font = "11px system-ui";
  for (const room of view.site.rooms) {
    g.beginPath();
    room.polygon.forEach(([x, y], i) => (i ? g.lineTo(f.px(x), f.py(y)) : g.moveTo(f.px(x), f.py(y))));
    g.closePath();
    g.fillStyle = "rgba(70, 130, 180, 0.07)";
    g.fill();
    const cx = room.polygon.reduce((s, p) => s + p[0], 0) / room.polygon.length;
    const cy = room.polygon.reduce((s, p) => s + p[1], 0) / room.polygon.length;
    g.fillStyle = "#4a6a8a";
    g.fillText(room.name, f.px(cx) - 6, f.py(cy) + 4);
  }
  for (const door of view.site.doors) {
    const [[ax, ay], [bx, by]] = door.segment;
    g.beginPath();
    g.moveTo(f.px(ax), f.py(ay));
    g.lineTo(f.px(bx), f.py(by));
    g.strokeStyle = door.open ? "#7cc47c" : "#c00";
    g.lineWidth = 3;
    g.stroke();
  }
  for (const m of view.site.landmarks) {
    g.fillStyle = "#b8860b";
    g.beginPath();
    g.moveTo(f.px(m.position[0]), f.py(m.position[1]) - 5);
    g.lineTo(f.px(m.position[0]) - 4, f.py(m.position[1]) + 3);
    g.lineTo(f.px(m.position[0]) + 4, f.py(m.position[1]) + 3);
    g.fill();
  }
  for (const st of view.site.stations) {
    g.strokeStyle = "#333";
    g.lineWidth = 1.5;
    g.strokeRect(f.px(st.pose[0]) - 4, f.py(st.pose[1]) - 4, 8, 8);
  }
}

function drawPlan(g, f) {
  const plan = view.plan;
  for (const action of plan.actions) {
    for (const move of action.moves) {
      g.beginPath();
      move.path_points.forEach(([x, y], i) => (i ? g.lineTo(f.px(x), f.py(y)) : g.moveTo(f.px(x), f.py(y))));
      const style = styleOf(move.robot);
      g.strokeStyle = style.colour;
      g.globalAlpha = 0.6;
      g.lineWidth = 2;
      g.setLineDash(style.dash);
      g.stroke();
      g.setLineDash([]);
      g.globalAlpha = 1;
    }
  }
  // belief ellipses along each robot's driving steps, about a dozen per robot
  for (const [robot, steps] of Object.entries(plan.trajectories)) {
    const driving = steps.filter((s) => s.action !== null);
    const every = Math.max(1, Math.floor(driving.length / 12));
    driving.forEach((s, i) => {
      if (i % every === 0) drawEllipse(g, f, s.mean[0], s.mean[1], s.cov, styleOf(robot), null);
    });
  }
}

function drawRobots(g, f) {
  const list = document.getElementById("robots");
  list.textContent = "";
  for (const r of view.site.robots) {
    const b = beliefAt(r.name, view.t);
    const style = styleOf(r.name), item = document.createElement("li");
    item.dataset.robot = r.name;
    item.dataset.colour = style.colour;
    item.dataset.dash = style.dash.join(" ");
    item.style.setProperty("--colour", style.colour);
    if (style.dash.length) item.appendChild(dashSwatch(style));
    let label;
    if (b) {
      const [x, y, th] = b.mean, radius = Math.max(r.radius * f.s, 4);
      drawEllipse(g, f, x, y, b.cov, style, "rgba(0, 0, 0, 0.08)");
      g.beginPath();
      g.arc(f.px(x), f.py(y), radius, 0, 2 * Math.PI);
      g.fillStyle = style.colour;
      g.fill();
      if (style.dash.length) {  // past the eighth robot: a ring in its line around the disc
        g.beginPath();
        g.arc(f.px(x), f.py(y), radius + 2.5, 0, 2 * Math.PI);
        g.strokeStyle = "#000";
        g.lineWidth = 1.5;
        g.setLineDash(style.dash);
        g.stroke();
        g.setLineDash([]);
      }
      g.beginPath();
      g.moveTo(f.px(x), f.py(y));
      g.lineTo(f.px(x + 0.8 * Math.cos(th)), f.py(y + 0.8 * Math.sin(th)));
      g.strokeStyle = "#000";
      g.lineWidth = 1.5;
      g.stroke();
      item.dataset.x = x.toFixed(3);
      item.dataset.y = y.toFixed(3);
      label = `${r.name} (${x.toFixed(1)}, ${y.toFixed(1)})`;
    } else {
      item.dataset.down = "true";
      label = `${r.name} (not in this plan)`;
    }
    item.appendChild(document.createTextNode(label));
    list.appendChild(item);
  }
}

// px: the Gantt chart's rows at most and at least (its labels' 11 px font and a gap), and the room
// below them for the time axis; the chart grows past its page height (160 px) to fit a fleet
const ROW_MAX = 28, ROW_MIN = 14, AXIS = 20, GANTT_HEIGHT = 160;

function drawGantt() {
  const canvas = document.getElementById("gantt"), g = canvas.getContext("2d");
  const robots = Object.keys(view.plan.schedule.robots);
  const height = Math.max(GANTT_HEIGHT, AXIS + 4 + ROW_MIN * robots.length);
  if (canvas.height !== height) canvas.height = height;  // resizing clears it too
  g.clearRect(0, 0, canvas.width, canvas.height);
  const span = Math.max(view.plan.schedule.makespan, 1e-6), left = 60, right = 10;
  const row = Math.min(ROW_MAX, (canvas.height - AXIS - 4) / Math.max(robots.length, 1));
  const px = (t) => left + (t / span) * (canvas.width - left - right);
  g.font = "11px system-ui";
  robots.forEach((robot, i) => {
    const y = 4 + i * row, style = styleOf(robot);
    g.fillStyle = "#222";
    g.fillText(robot, 6, y + row * 0.6);
    for (const m of view.plan.schedule.robots[robot].moves) {
      g.fillStyle = "#ddd";
      g.fillRect(px(m.ready), y + 4, px(m.start) - px(m.ready), row - 8);  // waiting
      g.fillStyle = style.colour;
      g.fillRect(px(m.start), y + 2, Math.max(px(m.end) - px(m.start), 1), row - 4);  // driving
      if (style.dash.length) {  // past the eighth robot: the bar outlined in its line
        g.strokeStyle = "#000";
        g.lineWidth = 1;
        g.setLineDash(style.dash);
        g.strokeRect(px(m.start), y + 2, Math.max(px(m.end) - px(m.start), 1), row - 4);
        g.setLineDash([]);
      }
      g.globalAlpha = 0.4;
      g.fillRect(px(m.end), y + 2, px(m.end + m.opens + m.service) - px(m.end), row - 4);  // at the station
      g.globalAlpha = 1;
      g.fillStyle = "#fff";
      if (px(m.end) - px(m.start) > 24) g.fillText(m.to, px(m.start) + 3, y + row * 0.6);
    }
  });
  g.strokeStyle = "#000";
  g.beginPath();
  g.moveTo(px(view.t), 0);
  g.lineTo(px(view.t), canvas.height);
  g.stroke();
  g.fillStyle = "#555";
  g.fillText(`0 s`, left, canvas.height - 4);
  g.fillText(`${span.toFixed(0)} s`, canvas.width - right - 40, canvas.height - 4);
}

function draw() {
  const canvas = document.getElementById("map"), g = canvas.getContext("2d");
  g.clearRect(0, 0, canvas.width, canvas.height);
  const f = frame(canvas);
  drawSite(g, f);
  if (view.plan) {
    drawPlan(g, f);
    drawRobots(g, f);
    drawGantt();
  }
  document.getElementById("clock").textContent = `${view.t.toFixed(1)} s`;
  document.body.dataset.drawn = String(view.revision);  // for tests: the revision on the canvas
}

async function loadPlan(revision) {
  view.plan = await get(`/plans/${view.planId}` + (revision === undefined ? "" : `?revision=${revision}`));
  view.revision = view.plan.revision ? view.plan.revision.number : 0;
  const slider = document.getElementById("time");
  slider.max = String(view.plan.schedule.makespan);
  slider.step = String(view.plan.dt);
  view.t = Math.min(view.t, view.plan.schedule.makespan);
  slider.value = String(view.t);
  document.getElementById("revision").textContent = String(view.revision);
  const cost = view.plan.cost.resimulated, span = view.plan.schedule.makespan;
  document.getElementById("summary").textContent =
    `plan ${view.planId}, revision ${view.revision}: ${view.plan.status}, cost ${cost.toFixed(1)}, ` +
    `makespan ${span.toFixed(1)} s, ${view.plan.actions.length} steps`;
  draw();
}

function listen() {
  const events = new EventSource(withToken(`/plans/${view.planId}/events`));
  const live = document.getElementById("live");
  events.onopen = () => live.classList.add("on");
  events.onerror = () => live.classList.remove("on");
  events.addEventListener("revision", (e) => {
    const info = JSON.parse(e.data);
    if (info.revision !== view.revision) loadPlan(info.revision);
  });
}

async function start() {
  view.site = await get("/site");
  document.getElementById("site").textContent = view.site.name;
  view.map = new Image();
  view.map.onload = draw;
  view.map.src = withToken("/site/map.png");
  document.getElementById("time").addEventListener("input", (e) => {
    view.t = Number(e.target.value);
    draw();
  });
  while (!view.planId) {
    const plans = await get("/plans");
    if (plans.length) view.planId = plans[plans.length - 1].id;
    else {
      document.getElementById("summary").textContent = "no plan yet: POST /plans to make one";
      draw();
      await new Promise((ok) => setTimeout(ok, 2000));
    }
  }
  await loadPlan();
  listen();
}

start().catch((err) => {
  document.getElementById("summary").textContent = "error: " + err.message;
});
