/* socialzoo episode viewer: plays the episodes of #replay-data (socialzoo.render.replay_data) on
   canvases. One shared clock, a step number, drives every panel: each panel shows its own episode
   at that step, or its last state once its episode has ended, so policies on the same scenario
   stay in step with each other. */
(function () {
  "use strict";

  const DATA = JSON.parse(document.getElementById("replay-data").textContent);
  const SCENE = DATA.scene;
  const ACTIONS = DATA.actions;
  const COLORS = {
    background: "#ffffff",
    wall: "#2d2d37",
    human: "#4678cd",
    humanEdge: "#19377d",
    robot: "#f58c1e",
    robotEdge: "#824100",
    robotMark: "#502300",
    other: "#a8a8b4",
    otherEdge: "#50505c",
    trail: "rgba(245, 140, 30, 0.45)",
    goal: "#23a541",
    carrot: "#d700c8",
    path: "#9a9aa6",
    laserHit: "#e12d2d",
    laserArea: "rgba(225, 45, 45, 0.07)",
    highlight: "#d7193c",
    grid: "#ececf1",
    text: "#1d1d24",
  };
  const FOLLOW_RADIUS = 6.0; // half the shorter side of the follow view, m
  const ARROW_SECONDS = 0.5; // velocity arrows show the motion over this time
  const SPEEDS = [0.1, 0.25, 0.5, 1, 2, 4, 8];
  // minSpan: the least value range a chart shows, in the series' unit, so that a nearly constant
  // series is drawn flat instead of its noise being blown up to the chart's height. For the
  // reward it is about half what one step at walking pace earns (5 per m x 1.5 m/s x 0.025 s):
  // a robot standing still wobbles by far less.
  const SERIES = [
    { key: "reward", label: "reward", color: "#2b2b33", minSpan: 0.1 },
    { key: "force", label: "force", color: "#d6404e", range: [0, 1] },
    { key: "blame", label: "blame", color: "#3f78d0", range: [0, 1] },
  ];
  const CHART_LABEL_SPACING = 18; // px between tick labels (10 px text): no two ever touch
  const MIN_RELATIVE_SPAN = 0.1; // a chart spans at least this fraction of its largest |value|
  const NICE_MANTISSAS = [1, 2, 2.5, 5];
  // [metric, heading, digits, kind]: the metric registry's (socialzoo.core.metrics), written by
  // socialzoo.render.replay_data.metric_rows.
  const METRIC_ROWS = DATA.metricRows || [];

  const episodes = DATA.episodes;
  const dt = episodes[0].dt;
  const maxStep = Math.max(...episodes.map((e) => e.steps));

  // ------------------------------------------------------------------ shared state
  const view = { camera: DATA.view === "map" ? "map" : "follow", zoom: 1, laser: true, path: true, velocity: true };
  let step = 0; // the clock, in steps (fractional while playing)
  let playing = false;
  let speed = 1;
  let lastTime = null;

  function actionName(a) {
    return a >= 0 && a < ACTIONS.names.length ? ACTIONS.names[a] : "velocity";
  }
  function actionColor(a) {
    return a >= 0 && a < ACTIONS.colors.length ? ACTIONS.colors[a] : ACTIONS.none;
  }
  function fmt(value, digits) {
    if (value === null || value === undefined) return "n/a";
    if (typeof value === "boolean") return value ? "yes" : "no";
    if (Number.isInteger(value)) return String(value);
    return value.toFixed(digits);
  }

  // The robust reward range shared by all panels: the success bonus (one large step) would
  // flatten everything else, so values beyond it are drawn clipped with their value. A range
  // that is (nearly) empty is widened by niceAxis.
  function rewardRange() {
    const values = [];
    for (const e of episodes) for (const v of e.reward) values.push(v);
    if (!values.length) return [0, 0];
    values.sort((a, b) => a - b);
    const q = (p) => values[Math.min(values.length - 1, Math.max(0, Math.round(p * (values.length - 1))))];
    const lo = Math.min(q(0.005), 0);
    const hi = Math.max(q(0.995), 0);
    const pad = 0.08 * (hi - lo);
    return [lo - pad, hi + pad];
  }
  SERIES[0].range = rewardRange();

  // A chart's value axis over [lo, hi]. A (nearly) empty range is widened, around its middle, to
  // at least minSpan, a tenth of the largest |value|, or 2 when all is 0, so that noise is not
  // blown up to the chart's height. Ticks are the multiples of a "nice" step (1, 2, 2.5 or 5 x
  // 10^k) inside the range, the step no smaller than an even split into maxTicks - 1 parts, so
  // there are at most maxTicks of them (at least 3 are allowed: see below) and their labels,
  // with just the digits the step needs, never overlap or repeat. Where fewer than two
  // multiples fall inside, the range is stretched to the multiples around it. Pure: tests call
  // it as window.socialzooReplay.niceAxis. Returns { lo, hi, step, ticks, labels }.
  function niceAxis(lo, hi, maxTicks, minSpan) {
    // Two would not do: a range around 0 always holds 0 and a multiple on each side once stretched.
    maxTicks = Math.max(3, Math.floor(maxTicks) || 3);
    if (!Number.isFinite(lo) || !Number.isFinite(hi)) {
      lo = Number.isFinite(lo) ? lo : Number.isFinite(hi) ? hi : 0;
      hi = lo;
    }
    // Far inside the doubles, so that the span and the steps below stay finite.
    lo = Math.min(1e300, Math.max(-1e300, lo));
    hi = Math.min(1e300, Math.max(-1e300, hi));
    if (lo > hi) [lo, hi] = [hi, lo];
    const magnitude = Math.max(Math.abs(lo), Math.abs(hi));
    let least = Math.max(minSpan || 0, MIN_RELATIVE_SPAN * magnitude);
    if (!(least > 0)) least = 2;
    if (hi - lo < least) {
      const mid = (lo + hi) / 2;
      lo = mid - least / 2;
      hi = mid + least / 2;
    }
    const raw = (hi - lo) / (maxTicks - 1);
    let exponent = Math.floor(Math.log10(raw));
    let m = NICE_MANTISSAS.findIndex((k) => k * 10 ** exponent >= raw * (1 - 1e-9));
    if (m < 0) { m = 0; exponent += 1; }
    const step = NICE_MANTISSAS[m] * 10 ** exponent;
    // A tick a thousandth of a step outside the range still counts (drawn on the edge).
    let first = Math.ceil(lo / step - 1e-3);
    let last = Math.floor(hi / step + 1e-3);
    if (last - first < 1) {
      first = Math.min(first, Math.floor(lo / step + 1e-3));
      last = Math.max(last, Math.ceil(hi / step - 1e-3));
      lo = Math.min(lo, first * step);
      hi = Math.max(hi, last * step);
    }
    const ticks = [];
    for (let k = first; k <= last; k++) ticks.push(k * step + 0); // + 0: no -0
    return { lo: lo, hi: hi, step: step, ticks: ticks, labels: tickLabels(ticks, exponent, NICE_MANTISSAS[m] === 2.5 ? 1 : 0) };
  }

  // Labels of ticks k x step, step = mantissa x 10^exponent (`extra` more digits for 2.5): fixed
  // decimals down to the step's last digit, or, for huge values or tiny steps, as many mantissa
  // digits in e-notation (9.50e+8, 1.00e+9).
  function tickLabels(ticks, exponent, extra) {
    const largest = Math.max(...ticks.map(Math.abs));
    if (largest >= 1e6 || exponent < -4) {
      const digits = Math.max(0, Math.floor(Math.log10(largest)) - exponent + extra);
      return ticks.map((v) => (v === 0 ? "0" : v.toExponential(digits)));
    }
    const decimals = Math.max(0, -exponent + extra);
    return ticks.map((v) => {
      const text = v.toFixed(decimals);
      return Number(text) === 0 ? (0).toFixed(decimals) : text; // rounding can give "-0.00"
    });
  }

  // ------------------------------------------------------------------ one episode's data
  class Episode {
    constructor(d) {
      this.d = d;
      this.steps = d.steps;
      this.frames = d.frameSteps.length;
      this.humans = d.humans;
      // 1/0 per kept state and human where people enter or leave; absent: everyone, always.
      this.present = d.humanPresent || null;
      this.rays = d.laser.angles.length;
      this.others = d.others ? d.others.length / (3 * this.frames) : 0; // the other robots
    }
    // The stored state shown at clock step s: the last one at or before s.
    frame(s) {
      const fs = this.d.frameSteps;
      const target = Math.min(s, this.steps);
      let lo = 0;
      let hi = fs.length - 1;
      while (lo < hi) {
        const mid = (lo + hi + 1) >> 1;
        if (fs[mid] <= target) lo = mid; else hi = mid - 1;
      }
      return lo;
    }
    isPresent(f, i) {
      return this.present === null || this.present[f * this.humans + i] === 1;
    }
    pose(f) {
      const r = this.d.robot;
      return [r[3 * f], r[3 * f + 1], r[3 * f + 2]];
    }
    // The step that led to state s (its action, target and values), or -1 for the start state.
    lastStep(s) {
      return Math.min(s, this.steps) - 1;
    }
  }

  // ------------------------------------------------------------------ drawing helpers
  function setupCanvas(canvas, cssHeight) {
    const ratio = window.devicePixelRatio || 1;
    const width = Math.max(50, canvas.clientWidth);
    canvas.style.height = cssHeight + "px";
    canvas.width = Math.round(width * ratio);
    canvas.height = Math.round(cssHeight * ratio);
    const ctx = canvas.getContext("2d");
    ctx.setTransform(ratio, 0, 0, ratio, 0, 0);
    return { ctx: ctx, w: width, h: cssHeight, canvas: canvas };
  }

  // Muted chart text on a veil of the chart's background, so a line under it does not blur it.
  function label(ctx, text, x, y, baseline) {
    ctx.textBaseline = baseline;
    const width = ctx.measureText(text).width;
    const x0 = ctx.textAlign === "right" ? x - width : x;
    const y0 = baseline === "top" ? y : baseline === "bottom" ? y - 10 : y - 5;
    ctx.fillStyle = "rgba(250, 250, 252, 0.85)";
    ctx.fillRect(x0 - 2, y0, width + 4, 10);
    ctx.fillStyle = "#6b6b78";
    ctx.fillText(text, x, y);
  }

  // An off-screen canvas the size of `box`, for what is drawn once and copied every frame.
  function layerOf(box) {
    const layer = document.createElement("canvas");
    layer.width = box.canvas.width;
    layer.height = box.canvas.height;
    const ctx = layer.getContext("2d");
    ctx.setTransform(box.canvas.width / box.w, 0, 0, box.canvas.height / box.h, 0, 0);
    return { ctx: ctx, w: box.w, h: box.h, canvas: layer };
  }

  function arrow(ctx, x0, y0, x1, y1, head) {
    const dx = x1 - x0;
    const dy = y1 - y0;
    const len = Math.hypot(dx, dy);
    if (len < 1) return;
    ctx.beginPath();
    ctx.moveTo(x0, y0);
    ctx.lineTo(x1, y1);
    const ux = dx / len;
    const uy = dy / len;
    const h = Math.min(head, len * 0.5);
    ctx.moveTo(x1, y1);
    ctx.lineTo(x1 - h * ux + 0.5 * h * uy, y1 - h * uy - 0.5 * h * ux);
    ctx.moveTo(x1, y1);
    ctx.lineTo(x1 - h * ux - 0.5 * h * uy, y1 - h * uy + 0.5 * h * ux);
    ctx.stroke();
  }

  // ------------------------------------------------------------------ a panel
  class Panel {
    constructor(data, index, root) {
      this.ep = new Episode(data);
      this.index = index;
      const el = document.createElement("section");
      el.className = "panel";
      el.dataset.index = String(index);
      const title = document.createElement("h2");
      const name = document.createElement("span");
      name.textContent = data.label;
      const outcome = document.createElement("span");
      const ok = Boolean(data.metrics && data.metrics.success); // true, or 1 from the CrowdNav task
      outcome.className = "outcome " + (ok ? "success" : "failure");
      outcome.textContent = (data.outcome || "") + ", " + (data.steps * dt).toFixed(2) + " s";
      title.append(name, outcome);
      this.scene = document.createElement("canvas");
      this.scene.className = "scene";
      this.scene.setAttribute("aria-label", data.label + ": the episode");
      this.timeline = document.createElement("canvas");
      this.timeline.className = "timeline";
      this.timeline.setAttribute("aria-label", data.label + ": sub-policy at each step");
      this.charts = document.createElement("canvas");
      this.charts.className = "charts";
      this.charts.setAttribute("aria-label", data.label + ": reward, force and blame");
      this.readout = document.createElement("div");
      this.readout.className = "readout";
      el.append(title, this.scene, this.timeline, this.charts, this.readout, this.metricsTable(data.metrics));
      root.append(el);
      this.el = el;
      for (const canvas of [this.timeline, this.charts]) seekOnDrag(canvas);
      this.scene.addEventListener("wheel", (ev) => {
        ev.preventDefault();
        view.zoom = Math.min(40, Math.max(0.05, view.zoom * Math.exp(-ev.deltaY * 0.0015)));
        drawAll();
      }, { passive: false });
      this.scene.addEventListener("dblclick", () => { view.zoom = 1; drawAll(); });
    }

    metricsTable(metrics) {
      const table = document.createElement("table");
      table.className = "metrics";
      const rows = METRIC_ROWS.filter(([key]) => metrics && key in metrics);
      for (let i = 0; i < rows.length; i += 2) {
        const tr = document.createElement("tr");
        for (const [key, label, digits, kind] of rows.slice(i, i + 2)) {
          const a = document.createElement("td");
          a.textContent = label;
          const b = document.createElement("td");
          const value = metrics[key];
          // A flag the CrowdNav task reports as 0.0 / 1.0 reads as one the other task reports as a bool.
          b.textContent = fmt(kind === "bool" && typeof value === "number" ? value !== 0 : value, digits);
          tr.append(a, b);
        }
        table.append(tr);
      }
      return table;
    }

    layout() {
      const width = Math.max(50, this.scene.clientWidth);
      let aspect = 0.72;
      if (view.camera === "map") {
        // The whole map: as tall as the map's shape asks, within reason.
        const [x0, y0, x1, y1] = SCENE.bounds;
        aspect = Math.min(0.9, Math.max(0.35, ((y1 - y0) / (x1 - x0)) * 1.04));
      }
      this.sceneBox = setupCanvas(this.scene, Math.round(width * aspect));
      this.timelineBox = setupCanvas(this.timeline, 22);
      this.chartsBox = setupCanvas(this.charts, 3 * 52);
      this.drawTimeline();
      this.drawCharts();
    }

    // World (m) -> canvas pixels for the current camera.
    camera(f) {
      const { w, h } = this.sceneBox;
      let cx;
      let cy;
      let scale;
      if (view.camera === "map") {
        const [x0, y0, x1, y1] = SCENE.bounds;
        cx = (x0 + x1) / 2;
        cy = (y0 + y1) / 2;
        scale = 0.97 * Math.min(w / (x1 - x0), h / (y1 - y0));
      } else {
        const p = this.ep.pose(f);
        cx = p[0];
        cy = p[1];
        scale = Math.min(w, h) / (2 * FOLLOW_RADIUS);
      }
      scale *= view.zoom;
      return {
        scale: scale,
        x: (x) => (x - cx) * scale + w / 2,
        y: (y) => (cy - y) * scale + h / 2,
      };
    }

    drawScene(s) {
      const ep = this.ep;
      const d = ep.d;
      const f = ep.frame(s);
      const last = ep.lastStep(s);
      const { ctx, w, h } = this.sceneBox;
      const cam = this.camera(f);
      const X = cam.x;
      const Y = cam.y;
      const px = cam.scale; // pixels per metre
      ctx.fillStyle = COLORS.background;
      ctx.fillRect(0, 0, w, h);
      ctx.lineCap = "round";
      ctx.lineJoin = "round";

      // Walls.
      const walls = SCENE.walls;
      ctx.strokeStyle = COLORS.wall;
      ctx.lineWidth = Math.max(1.5, 0.08 * px);
      ctx.beginPath();
      for (let i = 0; i < walls.length; i += 4) {
        ctx.moveTo(X(walls[i]), Y(walls[i + 1]));
        ctx.lineTo(X(walls[i + 2]), Y(walls[i + 3]));
      }
      ctx.stroke();

      // Global plan and the robot's trail so far.
      if (view.path) {
        const plan = d.plans[d.planIndex[f]];
        if (plan && plan.length >= 4) {
          ctx.strokeStyle = COLORS.path;
          ctx.lineWidth = 2;
          ctx.setLineDash([6, 5]);
          ctx.beginPath();
          ctx.moveTo(X(plan[0]), Y(plan[1]));
          for (let i = 2; i < plan.length; i += 2) ctx.lineTo(X(plan[i]), Y(plan[i + 1]));
          ctx.stroke();
          ctx.setLineDash([]);
        }
        ctx.strokeStyle = COLORS.trail;
        ctx.lineWidth = Math.max(2, 0.06 * px);
        ctx.beginPath();
        for (let k = 0; k <= f; k++) {
          const x = X(d.robot[3 * k]);
          const y = Y(d.robot[3 * k + 1]);
          if (k === 0) ctx.moveTo(x, y); else ctx.lineTo(x, y);
        }
        ctx.stroke();
      }

      // Goal.
      const gx = X(d.goal[0]);
      const gy = Y(d.goal[1]);
      ctx.strokeStyle = COLORS.goal;
      ctx.fillStyle = COLORS.goal;
      ctx.lineWidth = 2;
      ctx.beginPath();
      ctx.arc(gx, gy, Math.max(5, SCENE.goalRadius * px), 0, 2 * Math.PI);
      ctx.stroke();
      ctx.beginPath();
      ctx.arc(gx, gy, Math.max(2, 0.08 * px), 0, 2 * Math.PI);
      ctx.fill();

      const pose = ep.pose(f);
      // Laser: the scanned area, and dots where a ray hit something.
      if (view.laser && ep.rays) {
        const L = d.laser;
        const base = f * ep.rays;
        ctx.fillStyle = COLORS.laserArea;
        ctx.beginPath();
        ctx.moveTo(X(pose[0]), Y(pose[1]));
        for (let k = 0; k < ep.rays; k++) {
          const a = pose[2] + L.angles[k];
          const r = L.ranges[base + k];
          ctx.lineTo(X(pose[0] + r * Math.cos(a)), Y(pose[1] + r * Math.sin(a)));
        }
        ctx.closePath();
        ctx.fill();
        ctx.fillStyle = COLORS.laserHit;
        const dot = Math.max(1.2, Math.min(2.5, 0.04 * px));
        for (let k = 0; k < ep.rays; k++) {
          const r = L.ranges[base + k];
          if (r >= L.maxRange - 1e-3) continue;
          const a = pose[2] + L.angles[k];
          ctx.fillRect(X(pose[0] + r * Math.cos(a)) - dot, Y(pose[1] + r * Math.sin(a)) - dot, 2 * dot, 2 * dot);
        }
      }

      // Humans, their velocities, and the one followed or passed.
      const target = last >= 0 ? d.target[last] : -1;
      const hp = d.humanPos;
      const hv = d.humanVel;
      const base = f * ep.humans * 2;
      const hr = Math.max(3, SCENE.humanRadius * px);
      if (target >= 0 && ep.isPresent(f, target)) {
        ctx.strokeStyle = COLORS.highlight;
        ctx.lineWidth = 1.5;
        ctx.beginPath();
        ctx.moveTo(X(pose[0]), Y(pose[1]));
        ctx.lineTo(X(hp[base + 2 * target]), Y(hp[base + 2 * target + 1]));
        ctx.stroke();
      }
      for (let i = 0; i < ep.humans; i++) {
        if (!ep.isPresent(f, i)) continue;
        const x = X(hp[base + 2 * i]);
        const y = Y(hp[base + 2 * i + 1]);
        ctx.fillStyle = COLORS.human;
        ctx.strokeStyle = COLORS.humanEdge;
        ctx.lineWidth = 1;
        ctx.beginPath();
        ctx.arc(x, y, hr, 0, 2 * Math.PI);
        ctx.fill();
        ctx.stroke();
        if (i === target) {
          ctx.strokeStyle = COLORS.highlight;
          ctx.lineWidth = 2.5;
          ctx.beginPath();
          ctx.arc(x, y, hr + 4, 0, 2 * Math.PI);
          ctx.stroke();
        }
      }
      if (view.velocity) {
        ctx.strokeStyle = COLORS.humanEdge;
        ctx.lineWidth = 1.5;
        for (let i = 0; i < ep.humans; i++) {
          if (!ep.isPresent(f, i)) continue;
          const x = hp[base + 2 * i];
          const y = hp[base + 2 * i + 1];
          const vx = hv[base + 2 * i];
          const vy = hv[base + 2 * i + 1];
          arrow(ctx, X(x), Y(y), X(x + ARROW_SECONDS * vx), Y(y + ARROW_SECONDS * vy), 6);
        }
      }

      // The other robots, then this one: footprints (length along the heading) with a chevron,
      // and this one's velocity.
      for (let k = 0; k < ep.others; k++) {
        const o = d.others;
        const at = 3 * (f * ep.others + k);
        this.drawRobot(ctx, X, Y, px, [o[at], o[at + 1], o[at + 2]], COLORS.other, COLORS.otherEdge);
      }
      this.drawRobot(ctx, X, Y, px, pose, COLORS.robot, COLORS.robotEdge);
      if (view.velocity) {
        const v = d.robotVel[2 * f];
        ctx.strokeStyle = COLORS.robotEdge;
        ctx.lineWidth = 2;
        arrow(ctx, X(pose[0]), Y(pose[1]),
          X(pose[0] + ARROW_SECONDS * v * Math.cos(pose[2])), Y(pose[1] + ARROW_SECONDS * v * Math.sin(pose[2])), 7);
      }

      // Carrot (the local target on the plan), where the episodes have one (a task without a navigator
      // keeps its goal there: the legend leaves the carrot out, and so does the picture).
      if (!DATA.legend || DATA.legend.includes("carrot")) {
        ctx.fillStyle = COLORS.carrot;
        ctx.strokeStyle = "#6e0064";
        ctx.lineWidth = 1;
        ctx.beginPath();
        ctx.arc(X(d.carrot[2 * f]), Y(d.carrot[2 * f + 1]), Math.max(3.5, 0.1 * px), 0, 2 * Math.PI);
        ctx.fill();
        ctx.stroke();
      }

      this.drawHud(ctx, w, h, s, last);
    }

    drawRobot(ctx, X, Y, px, pose, fill, edge) {
      // Never smaller than 10 pixels long, so the robot stays visible in the map view.
      const grow = Math.max(1, 10 / (SCENE.robotLength * px));
      const hl = 0.5 * SCENE.robotLength * grow;
      const hw = 0.5 * SCENE.robotWidth * grow;
      const c = Math.cos(pose[2]);
      const sn = Math.sin(pose[2]);
      const at = (a, b) => [X(pose[0] + a * c - b * sn), Y(pose[1] + a * sn + b * c)];
      const corners = [at(hl, hw), at(-hl, hw), at(-hl, -hw), at(hl, -hw)];
      ctx.fillStyle = fill;
      ctx.strokeStyle = edge;
      ctx.lineWidth = Math.max(1, 0.03 * px);
      ctx.beginPath();
      corners.forEach(([x, y], k) => (k ? ctx.lineTo(x, y) : ctx.moveTo(x, y)));
      ctx.closePath();
      ctx.fill();
      ctx.stroke();
      const chevron = [at(0.85 * hl, 0), at(-0.35 * hl, 0.6 * hw), at(-0.1 * hl, 0), at(-0.35 * hl, -0.6 * hw)];
      ctx.fillStyle = COLORS.robotMark;
      ctx.beginPath();
      chevron.forEach(([x, y], k) => (k ? ctx.lineTo(x, y) : ctx.moveTo(x, y)));
      ctx.closePath();
      ctx.fill();
    }

    drawHud(ctx, w, h, s, last) {
      const ep = this.ep;
      const shown = Math.min(s, ep.steps);
      const lines = [];
      const action = last >= 0 ? ep.d.action[last] : null;
      lines.push([action === null ? "start" : actionName(action), action === null ? COLORS.text : actionColor(action)]);
      lines.push(["t = " + (shown * dt).toFixed(2) + " s   step " + shown, COLORS.text]);
      ctx.font = "600 15px system-ui, sans-serif";
      const width = Math.max(...lines.map(([t]) => ctx.measureText(t).width)) + 16;
      ctx.fillStyle = "rgba(255, 255, 255, 0.88)";
      ctx.strokeStyle = "#c8c8d0";
      ctx.lineWidth = 1;
      ctx.fillRect(6, 6, width, 44);
      ctx.strokeRect(6.5, 6.5, width, 44);
      lines.forEach(([text, color], k) => {
        ctx.fillStyle = color;
        ctx.font = (k === 0 ? "600 15px" : "12px") + " system-ui, sans-serif";
        ctx.fillText(text, 14, 24 + 18 * k);
      });
      if (s > ep.steps) {
        const text = "episode over at " + (ep.steps * dt).toFixed(2) + " s: " + (ep.d.outcome || "ended");
        ctx.font = "600 14px system-ui, sans-serif";
        const tw = ctx.measureText(text).width + 20;
        ctx.fillStyle = "rgba(29, 29, 36, 0.78)";
        ctx.fillRect((w - tw) / 2, h - 38, tw, 28);
        ctx.fillStyle = "#ffffff";
        ctx.fillText(text, (w - tw) / 2 + 10, h - 19);
      }
    }

    // The sub-policy timeline: one coloured run per stretch of equal actions, on the shared axis.
    drawTimeline() {
      this.timelineLayer = layerOf(this.timelineBox);
      const { ctx, w, h } = this.timelineLayer;
      const actions = this.ep.d.action;
      const xOf = (k) => (k / Math.max(1, maxStep)) * w;
      ctx.clearRect(0, 0, w, h);
      ctx.fillStyle = COLORS.grid;
      ctx.fillRect(0, 0, w, h);
      let start = 0;
      for (let k = 1; k <= actions.length; k++) {
        if (k === actions.length || actions[k] !== actions[start]) {
          ctx.fillStyle = actionColor(actions[start]);
          ctx.fillRect(xOf(start), 2, Math.max(1, xOf(k) - xOf(start)), h - 4);
          start = k;
        }
      }
    }

    drawCharts() {
      this.chartsLayer = layerOf(this.chartsBox);
      const { ctx, w, h } = this.chartsLayer;
      const d = this.ep.d;
      const band = h / SERIES.length;
      ctx.clearRect(0, 0, w, h);
      ctx.font = "10px system-ui, sans-serif";
      SERIES.forEach((series, i) => {
        const top = i * band + 3;
        const height = band - 8;
        const maxTicks = Math.floor(height / CHART_LABEL_SPACING) + 1;
        const axis = niceAxis(series.range[0], series.range[1], maxTicks, series.minSpan);
        const { lo, hi } = axis;
        const yOf = (v) => top + height * (1 - (Math.min(hi, Math.max(lo, v)) - lo) / (hi - lo));
        ctx.fillStyle = "#fafafc";
        ctx.fillRect(0, top, w, height);
        for (const v of axis.ticks) {
          ctx.strokeStyle = v === 0 && lo < 0 ? "#d4d4dc" : COLORS.grid;
          ctx.lineWidth = 1;
          ctx.beginPath();
          ctx.moveTo(0, Math.round(yOf(v)) + 0.5);
          ctx.lineTo(w, Math.round(yOf(v)) + 0.5);
          ctx.stroke();
        }
        const values = d[series.key];
        ctx.strokeStyle = series.color;
        ctx.lineWidth = 1.2;
        ctx.beginPath();
        for (let k = 0; k < values.length; k++) {
          const x = ((k + 1) / Math.max(1, maxStep)) * w;
          if (k === 0) ctx.moveTo(x, yOf(values[k])); else ctx.lineTo(x, yOf(values[k]));
        }
        ctx.stroke();
        // Values beyond the robust range (the success bonus): a marker, with the value where it
        // does not run into the previous one's nor into the tick labels.
        ctx.fillStyle = series.color;
        ctx.textBaseline = "alphabetic";
        const gutter = Math.max(...axis.labels.map((t) => ctx.measureText(t).width)) + 8;
        let textEnd = -Infinity;
        for (let k = 0; k < values.length; k++) {
          if (values[k] > hi || values[k] < lo) {
            const x = ((k + 1) / Math.max(1, maxStep)) * w;
            const up = values[k] > hi;
            const y = up ? top + 1 : top + height - 1;
            ctx.beginPath();
            ctx.moveTo(x, y);
            ctx.lineTo(x - 4, y + (up ? 7 : -7));
            ctx.lineTo(x + 4, y + (up ? 7 : -7));
            ctx.fill();
            const text = fmt(values[k], 1);
            const width = ctx.measureText(text).width;
            const tx = Math.min(x + 6, w - gutter - width - 2);
            if (tx > textEnd + 4) {
              ctx.fillText(text, tx, up ? top + 10 : top + height - 2);
              textEnd = tx + width;
            }
          }
        }
        // Tick labels at the right edge (kept inside the band) and the name at the left, on a
        // veil over the line.
        ctx.textAlign = "right";
        axis.ticks.forEach((v, t) => {
          const y = yOf(v);
          if (y - top < 6) label(ctx, axis.labels[t], w - 3, top + 1, "top");
          else if (top + height - y < 6) label(ctx, axis.labels[t], w - 3, top + height - 1, "bottom");
          else label(ctx, axis.labels[t], w - 3, y, "middle");
        });
        ctx.textAlign = "left";
        label(ctx, series.label, 4, top + 1, "top");
      });
      ctx.textAlign = "left";
      ctx.textBaseline = "alphabetic";
    }

    // The cursor over the pre-drawn timeline and charts.
    drawCursors(s) {
      for (const [box, layer] of [[this.timelineBox, this.timelineLayer], [this.chartsBox, this.chartsLayer]]) {
        const { ctx, w, h } = box;
        ctx.clearRect(0, 0, w, h);
        ctx.drawImage(layer.canvas, 0, 0, w, h);
        const x = Math.round((s / Math.max(1, maxStep)) * w) + 0.5;
        ctx.strokeStyle = "#111111";
        ctx.lineWidth = 1;
        ctx.beginPath();
        ctx.moveTo(x, 0);
        ctx.lineTo(x, h);
        ctx.stroke();
      }
    }

    drawReadout(s) {
      const ep = this.ep;
      const d = ep.d;
      const last = ep.lastStep(s);
      const f = ep.frame(s);
      const parts = ["v " + d.robotVel[2 * f].toFixed(2) + " m/s"];
      if (last >= 0) {
        parts.unshift(actionName(d.action[last]));
        parts.push("reward " + d.reward[last].toFixed(3), "force " + d.force[last].toFixed(3),
          "blame " + d.blame[last].toFixed(3));
        if (d.collisions[last] > 0) parts.push(d.collisions[last] + " in collision");
        if (d.wall[last]) parts.push("wall contact");
      }
      this.readout.textContent = parts.join(" \u00b7 ");
    }

    draw(s) {
      this.drawScene(s);
      this.drawCursors(s);
      this.drawReadout(s);
    }
  }

  // ------------------------------------------------------------------ page
  document.title = DATA.title;
  document.getElementById("title").textContent = DATA.title;
  document.getElementById("subtitle").textContent = DATA.subtitle;
  const legend = document.getElementById("legend");
  const swatches = ACTIONS.names.map((name, i) => [name, ACTIONS.colors[i]]);
  const bodies = {robot: COLORS.robot, "other robots": COLORS.other, humans: COLORS.human, goal: COLORS.goal, carrot: COLORS.carrot,
    laser: COLORS.laserHit, "followed / passed": COLORS.highlight};
  // The task's own legend (no sub-policies on a velocity task, no laser where none was scanned).
  for (const name of DATA.legend || Object.keys(bodies)) swatches.push([name, bodies[name]]);
  for (const [name, color] of swatches) {
    const item = document.createElement("span");
    const sw = document.createElement("span");
    sw.className = "swatch";
    sw.style.background = color;
    item.append(sw, document.createTextNode(name));
    legend.append(item);
  }

  const root = document.getElementById("panels");
  root.dataset.count = String(episodes.length);
  const panels = episodes.map((e, i) => new Panel(e, i, root));
  const scrub = document.getElementById("scrub");
  const clock = document.getElementById("clock");
  const playButton = document.getElementById("play");
  scrub.max = String(maxStep);
  const stride = Math.max(1, episodes[0].frameSteps.length > 1 ? episodes[0].frameSteps[1] : 1);

  function drawAll() {
    const s = Math.max(0, Math.min(maxStep, Math.floor(step)));
    scrub.value = String(s);
    clock.textContent = "t = " + (s * dt).toFixed(2) + " s / " + (maxStep * dt).toFixed(2) + " s";
    for (const p of panels) p.draw(s);
  }

  function layoutAll() {
    for (const p of panels) p.layout();
    drawAll();
  }

  function seek(s) {
    step = Math.max(0, Math.min(maxStep, Number(s)));
    lastTime = null;
    drawAll();
  }

  function seekOnDrag(canvas) {
    const go = (ev) => {
      const rect = canvas.getBoundingClientRect();
      seek(Math.round(((ev.clientX - rect.left) / rect.width) * maxStep));
    };
    canvas.addEventListener("pointerdown", (ev) => {
      canvas.setPointerCapture(ev.pointerId);
      go(ev);
    });
    canvas.addEventListener("pointermove", (ev) => {
      if (canvas.hasPointerCapture(ev.pointerId)) go(ev);
    });
  }

  function tick(now) {
    if (!playing) return;
    if (lastTime !== null) step += ((now - lastTime) / 1000) * (speed / dt);
    lastTime = now;
    if (step >= maxStep) {
      step = maxStep;
      pause();
    }
    drawAll();
    if (playing) requestAnimationFrame(tick);
  }

  function play() {
    if (playing) return;
    if (step >= maxStep) step = 0;
    playing = true;
    lastTime = null;
    playButton.textContent = "Pause";
    requestAnimationFrame(tick);
  }

  function pause() {
    playing = false;
    lastTime = null;
    playButton.textContent = "Play";
  }

  playButton.addEventListener("click", () => (playing ? pause() : play()));
  document.getElementById("back").addEventListener("click", () => { pause(); seek(Math.floor(step) - stride); });
  document.getElementById("forward").addEventListener("click", () => { pause(); seek(Math.floor(step) + stride); });
  scrub.addEventListener("input", () => { pause(); seek(Number(scrub.value)); });

  const speedSelect = document.getElementById("speed");
  for (const value of SPEEDS) {
    const option = document.createElement("option");
    option.value = String(value);
    option.textContent = value + "\u00d7";
    if (value === 1) option.selected = true;
    speedSelect.append(option);
  }
  speedSelect.addEventListener("change", () => { speed = Number(speedSelect.value); });

  const cameraSelect = document.getElementById("camera");
  cameraSelect.value = view.camera;
  function setCamera(camera) {
    view.camera = camera === "map" ? "map" : "follow";
    cameraSelect.value = view.camera;
    view.zoom = 1;
    layoutAll();
  }
  cameraSelect.addEventListener("change", () => setCamera(cameraSelect.value));
  for (const [id, key] of [["show-laser", "laser"], ["show-path", "path"], ["show-velocity", "velocity"]]) {
    const box = document.getElementById(id);
    box.addEventListener("change", () => { view[key] = box.checked; drawAll(); });
  }

  document.addEventListener("keydown", (ev) => {
    if (ev.target instanceof HTMLSelectElement) return;
    if (ev.key === " ") {
      ev.preventDefault();
      if (playing) pause(); else play();
    } else if (ev.key === "ArrowRight" || ev.key === "ArrowLeft") {
      if (ev.target === scrub) return; // the range input steps itself
      ev.preventDefault();
      pause();
      seek(Math.floor(step) + (ev.key === "ArrowRight" ? stride : -stride));
    } else if (ev.key === "Home") {
      seek(0);
    } else if (ev.key === "End") {
      seek(maxStep);
    }
  });

  let resizeTimer = null;
  window.addEventListener("resize", () => {
    clearTimeout(resizeTimer);
    resizeTimer = setTimeout(layoutAll, 100);
  });

  layoutAll();

  // For scripts and tests: the clock and the playback, from outside the page.
  window.socialzooReplay = {
    seek: seek,
    play: play,
    pause: pause,
    setCamera: setCamera,
    niceAxis: niceAxis,
    get step() { return Math.floor(step); },
    get playing() { return playing; },
    maxStep: maxStep,
    panels: panels.length,
  };
  document.body.dataset.ready = "true";
})();
