// LAMP replay viewer: draws a recorded run (lamp-recording/1) on a canvas. Self-contained:
// the data is the JSON in #lamp-data, nothing is fetched. The shown state is mirrored in
// #state (data-row, data-segment, data-time, data-robots, data-objects) after every draw.
(function () {
  "use strict";
  const D = JSON.parse(document.getElementById("lamp-data").textContent);

  function decode(b64, Type) {
    const bin = atob(b64);
    const bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
    return new Type(bytes.buffer);
  }
  const times = decode(D.times, Float64Array);
  const robots = decode(D.robots, Float32Array);   // rows x N x 2
  const poses = decode(D.object_poses, Float32Array); // rows x K x 3
  // rows x N: the object whose sub-team each robot is in (-1: none); concurrent runs only
  const teams = D.robot_team ? decode(D.robot_team, Int16Array) : null;
  const N = D.n_robots, K = D.n_objects, S = D.n_rows;
  const segRows = D.segment_rows, segs = D.segments, plans = D.plans;
  const G = segs.length;
  const $ = (id) => document.getElementById(id);
  const canvas = $("view"), ctx = canvas.getContext("2d");
  const layerIds = ["path", "verified", "penalised", "contacts", "trails", "inflated"];

  const st = { row: 0, time: 0, playing: false, speed: 4, scale: 1, ox: 0, oy: 0, last: null };

  // ---------------------------------------------------------------- timeline
  function segmentOfRow(row) { // the segment whose rows (start, end] hold row; row 0: 0
    if (G === 0) return -1;
    let lo = 0, hi = segRows.length; // first index with segRows[i] >= row
    while (lo < hi) { const m = (lo + hi) >> 1; if (segRows[m] < row) lo = m + 1; else hi = m; }
    return Math.min(Math.max(lo - 1, 0), G - 1);
  }
  function rowAtTime(t) { // the last row at or before t
    let lo = 0, hi = S;
    while (lo < hi) { const m = (lo + hi) >> 1; if (times[m] <= t + 1e-9) lo = m + 1; else hi = m; }
    return Math.max(lo - 1, 0);
  }
  function seekRow(row) {
    st.row = Math.min(Math.max(Math.round(row), 0), S - 1);
    st.time = times[st.row];
    draw();
  }
  function seekSegment(k) { // the end of segment k, drawn with segment k
    if (G === 0) return seekRow(0);
    k = Math.min(Math.max(k, 0), G - 1);
    seekRow(segRows[k + 1]);
  }
  function setPlaying(on) {
    st.playing = on && S > 1;
    if (st.playing && st.row >= S - 1) { st.row = 0; st.time = 0; }
    $("play").innerHTML = st.playing ? "&#10074;&#10074; pause" : "&#9654; play";
    st.last = null;
    if (st.playing) requestAnimationFrame(tick);
    draw();
  }
  function tick(now) {
    if (!st.playing) return;
    if (st.last !== null) {
      st.time += ((now - st.last) / 1000) * st.speed;
      if (st.time >= times[S - 1]) { st.time = times[S - 1]; st.row = S - 1; setPlaying(false); return; }
      st.row = rowAtTime(st.time);
      draw();
    }
    st.last = now;
    requestAnimationFrame(tick);
  }

  // ------------------------------------------------------------------- view
  // Coordinates are CSS pixels; the canvas has devicePixelRatio device pixels per CSS pixel.
  const view = { w: 1, h: 1, dpr: 1 };
  function resize() {
    const r = canvas.getBoundingClientRect();
    view.dpr = window.devicePixelRatio || 1;
    view.w = Math.max(1, r.width); view.h = Math.max(1, r.height);
    canvas.width = Math.max(1, Math.round(view.w * view.dpr));
    canvas.height = Math.max(1, Math.round(view.h * view.dpr));
  }
  function fit() {
    const [W, H] = D.workspace, m = 0.03 * Math.max(W, H);
    st.scale = Math.min(view.w / (W + 2 * m), view.h / (H + 2 * m));
    st.ox = (view.w - st.scale * W) / 2;
    st.oy = (view.h + st.scale * H) / 2;
  }
  function zoom(f, cx, cy) {
    if (cx === undefined) { cx = view.w / 2; cy = view.h / 2; }
    st.ox = cx - (cx - st.ox) * f;
    st.oy = cy - (cy - st.oy) * f;
    st.scale *= f;
    draw();
  }
  const sx = (x) => st.ox + st.scale * x;
  const sy = (y) => st.oy - st.scale * y;
  function toScreen(x, y) { return [sx(x), sy(y)]; }

  // ------------------------------------------------------------------ shapes
  function placed(outline, x, y, th) {
    const c = Math.cos(th), s = Math.sin(th);
    return outline.map(([px, py]) => [x + c * px - s * py, y + s * px + c * py]);
  }
  function polyPath(pts) {
    ctx.beginPath();
    pts.forEach(([x, y], i) => (i ? ctx.lineTo(sx(x), sy(y)) : ctx.moveTo(sx(x), sy(y))));
    ctx.closePath();
  }
  function circlePath(x, y, r) {
    ctx.beginPath();
    ctx.arc(sx(x), sy(y), Math.max(r * st.scale, 0.5), 0, 2 * Math.PI);
  }
  function shapeAt(o, pose) {
    if (o.circle !== undefined) circlePath(pose[0], pose[1], o.circle);
    else polyPath(placed(o.outline, pose[0], pose[1], pose[2]));
  }
  function polyline(pts, color, width) {
    if (pts.length < 2) return;
    ctx.strokeStyle = color; ctx.lineWidth = width;
    ctx.beginPath();
    pts.forEach(([x, y], i) => (i ? ctx.lineTo(sx(x), sy(y)) : ctx.moveTo(sx(x), sy(y))));
    ctx.stroke();
  }
  function edges(list, color) {
    ctx.strokeStyle = color; ctx.lineWidth = 1.6;
    ctx.beginPath();
    for (const [[x0, y0], [x1, y1]] of list) { ctx.moveTo(sx(x0), sy(y0)); ctx.lineTo(sx(x1), sy(y1)); }
    ctx.stroke();
  }
  const on = (name) => $("layer-" + name).checked;
  const robotAt = (row, i) => [robots[(row * N + i) * 2], robots[(row * N + i) * 2 + 1]];
  const poseAt = (row, k) => [0, 1, 2].map((j) => poses[(row * K + k) * 3 + j]);

  // A lifelong run's tasks (result.tasks): each one's status at time t, and the goal an
  // object serves then (its task started last; before any, its own goal).
  function tasksAt(t) {
    return (D.tasks || []).map((k) => ({ ...k, now:
      k.done_s !== null && k.done_s <= t ? k.status :
      k.start_s !== null && k.start_s <= t ? "active" :
      k.release_s <= t ? "queued" : "future" }));
  }
  function goalAt(k, tasks) {
    let goal = D.objects[k].goal;
    for (const task of tasks) if (task.object === k && task.now !== "queued" && task.now !== "future") goal = task.goal;
    return goal;
  }

  // ------------------------------------------------------------------- draw
  function draw() {
    const C = D.colors, row = st.row, g = segmentOfRow(row);
    const seg = g >= 0 ? segs[g] : null, plan = seg && seg.plan >= 0 ? plans[seg.plan] : null;
    const [W, H] = D.workspace, R = D.robot_radius;
    ctx.setTransform(view.dpr, 0, 0, view.dpr, 0, 0);
    ctx.fillStyle = "#eef0f3"; ctx.fillRect(0, 0, view.w, view.h);
    ctx.fillStyle = "#ffffff"; ctx.fillRect(sx(0), sy(H), W * st.scale, H * st.scale);
    ctx.lineJoin = "round"; ctx.lineCap = "round";
    if (on("inflated")) { // Minkowski sum with the robot disk: a stroke 2R wide, round joins
      ctx.fillStyle = C.inflated; ctx.strokeStyle = C.inflated; ctx.lineWidth = 2 * R * st.scale;
      for (const o of D.obstacles) { shapeAt(o, o.at || [0, 0, 0]); ctx.fill(); ctx.stroke(); }
      ctx.strokeRect(sx(0), sy(H), W * st.scale, H * st.scale);
    }
    ctx.fillStyle = C.obstacle;
    for (const o of D.obstacles) { shapeAt(o, o.at || [0, 0, 0]); ctx.fill(); }
    ctx.strokeStyle = "#000"; ctx.lineWidth = 1.5;
    ctx.strokeRect(sx(0), sy(H), W * st.scale, H * st.scale);
    const t = times[row], tasks = tasksAt(t), out = $("state");
    D.objects.forEach((o, k) => {
      const active = seg && seg.object === k;
      ctx.setLineDash([5, 4]); ctx.strokeStyle = o.color; ctx.lineWidth = active ? 2 : 1;
      shapeAt(o, o.start); ctx.stroke(); ctx.setLineDash([]);
      ctx.strokeStyle = C.goal; ctx.lineWidth = active ? 2.4 : 1.4;
      shapeAt(o, goalAt(k, tasks)); ctx.stroke();
    });
    if (plan && on("path")) polyline(plan.path, C.path, 5);
    if (plan && on("verified")) edges(plan.verified, C.verified);
    if (plan && on("penalised")) edges(plan.penalised, C.penalised);
    if (on("trails")) {
      const lo = Math.max(0, row - Math.round(D.trail_s / D.row_dt_s));
      for (let i = 0; i < N; i++) {
        const pts = [];
        for (let r = lo; r <= row; r++) pts.push(robotAt(r, i));
        polyline(pts, C.trail, 1.2);
      }
    }
    if (seg && on("contacts")) {
      for (const p of seg.pushes) { ctx.setLineDash([2, 3]); polyline(p, C.contact, 1); }
      ctx.setLineDash([]);
      ctx.strokeStyle = C.contact; ctx.lineWidth = 1.5;
      for (const [x, y] of seg.contacts) {
        const [X, Y] = toScreen(x, y);
        ctx.beginPath(); ctx.moveTo(X - 4, Y - 4); ctx.lineTo(X + 4, Y + 4);
        ctx.moveTo(X - 4, Y + 4); ctx.lineTo(X + 4, Y - 4); ctx.stroke();
      }
    }
    const shownObjects = [];
    D.objects.forEach((o, k) => {
      const p = poseAt(row, k);
      shownObjects.push(p);
      ctx.globalAlpha = 0.85; ctx.fillStyle = o.color; shapeAt(o, p); ctx.fill();
      ctx.globalAlpha = 1; ctx.strokeStyle = "#000"; ctx.lineWidth = seg && seg.object === k ? 2.2 : 0.8;
      ctx.stroke();
      polyline([[p[0], p[1]], [p[0] + o.tick * Math.cos(p[2]), p[1] + o.tick * Math.sin(p[2])]], "#000", 1.2);
    });
    const shownRobots = [];
    const rPx = Math.max(R * st.scale, D.min_robot_px);
    for (let i = 0; i < N; i++) {
      const [x, y] = robotAt(row, i);
      shownRobots.push([x, y]);
      ctx.beginPath(); ctx.arc(sx(x), sy(y), rPx, 0, 2 * Math.PI);
      const team = teams ? teams[row * N + i] : -1;
      ctx.fillStyle = team >= 0 ? D.objects[team].color : C.robot; ctx.fill();
      ctx.strokeStyle = team >= 0 ? "#000" : "#fff"; ctx.lineWidth = 0.8; ctx.stroke();
    }
    const event = seg && seg.outcome !== "continue" ? "  [" + seg.outcome + "]" : "";
    $("clock").textContent = "t = " + times[row].toFixed(2) + " s   " +
      (seg ? "segment " + (g + 1) + "/" + G + "   object " + (seg.object + 1) + "/" + K : "no segment executed") + event;
    if (D.tasks) {
      const n = (what) => tasks.filter((k) => k.now === what).length;
      $("tasks").textContent = "tasks: " + n("queued") + " queued, " + n("active") + " active, " +
        n("done") + " done" + (n("failed") ? ", " + n("failed") + " failed" : "") +
        " of " + tasks.length + " (" + n("future") + " not yet released)";
      out.dataset.tasks = JSON.stringify(tasks.map((k) => k.now));
    }
    $("scrub").value = String(row);
    document.querySelectorAll("#segments tbody tr").forEach((tr, i) => tr.classList.toggle("current", i === g));
    out.dataset.row = String(row);
    out.dataset.segment = String(g);
    out.dataset.time = String(times[row]);
    out.dataset.playing = String(st.playing);
    out.dataset.robots = JSON.stringify(shownRobots);
    out.dataset.objects = JSON.stringify(shownObjects);
    out.dataset.view = JSON.stringify({ scale: st.scale, ox: st.ox, oy: st.oy, robot_px: rPx });
    out.dataset.layers = layerIds.filter(on).join(",");
  }

  // ------------------------------------------------------------------- panel
  function buildPanel() {
    $("title").textContent = D.title;
    const out = $("outcome");
    out.textContent = D.outcome; out.className = D.success ? "success" : "failed";
    const r = D.result;
    $("totals").textContent = "planning " + r.total_planning_time_s.toFixed(2) + " s total, " +
      r.replans + " replans, makespan " + r.makespan + " steps, wall " + r.wall_time_s.toFixed(1) + " s";
    const body = document.querySelector("#segments tbody");
    segs.forEach((s, i) => {
      const tr = document.createElement("tr");
      const cells = [i + 1, s.object + 1, s.planning_s.toFixed(3), s.sim_s.toFixed(2),
        s.drift[0].toFixed(3),
        [s.replanned ? "new plan" : "", s.outcome !== "continue" ? s.outcome : ""]
          .filter(Boolean).join(", ") || "-"];
      cells.forEach((c, j) => {
        const td = document.createElement("td"); td.textContent = String(c);
        if (j === 5) td.className = "event-" + s.outcome;
        tr.appendChild(td);
      });
      tr.addEventListener("click", () => { setPlaying(false); seekSegment(i); });
      body.appendChild(tr);
    });
    $("scrub").max = String(S - 1);
    const swatch = { path: "path", verified: "verified", penalised: "penalised",
      contacts: "contact", trails: "trail", inflated: "inflated" };
    layerIds.forEach((n) => {
      const sw = document.createElement("span");
      sw.className = "swatch"; sw.style.background = D.colors[swatch[n]];
      $("layer-" + n).after(sw);
    });
  }

  // ------------------------------------------------------------------ events
  function bind() {
    $("play").addEventListener("click", () => setPlaying(!st.playing));
    $("prev").addEventListener("click", () => {
      setPlaying(false);
      const g = segmentOfRow(st.row);
      if (g <= 0) seekRow(0); else seekSegment(g - 1);
    });
    $("next").addEventListener("click", () => {
      setPlaying(false);
      const g = segmentOfRow(st.row);
      seekSegment(st.row < segRows[g + 1] ? g : g + 1);
    });
    $("scrub").addEventListener("input", (e) => {
      const row = Number(e.target.value); // read before pausing redraws the slider
      setPlaying(false);
      seekRow(row);
    });
    $("speed").addEventListener("change", (e) => { st.speed = Number(e.target.value); });
    $("zoom-in").addEventListener("click", () => zoom(1.5));
    $("zoom-out").addEventListener("click", () => zoom(1 / 1.5));
    $("fit").addEventListener("click", () => { fit(); draw(); });
    layerIds.forEach((n) => $("layer-" + n).addEventListener("change", draw));
    canvas.addEventListener("wheel", (e) => {
      e.preventDefault();
      const r = canvas.getBoundingClientRect();
      zoom(Math.exp(-e.deltaY * 0.0015), e.clientX - r.left, e.clientY - r.top);
    }, { passive: false });
    let drag = null;
    canvas.addEventListener("pointerdown", (e) => {
      drag = [e.clientX, e.clientY]; canvas.classList.add("dragging"); canvas.setPointerCapture(e.pointerId);
    });
    canvas.addEventListener("pointermove", (e) => {
      if (!drag) return;
      st.ox += e.clientX - drag[0]; st.oy += e.clientY - drag[1]; drag = [e.clientX, e.clientY]; draw();
    });
    const end = () => { drag = null; canvas.classList.remove("dragging"); };
    canvas.addEventListener("pointerup", end);
    canvas.addEventListener("pointercancel", end);
    window.addEventListener("keydown", (e) => {
      if (e.key === " ") { e.preventDefault(); setPlaying(!st.playing); }
      else if (e.key === "ArrowRight") seekRow(st.row + 1);
      else if (e.key === "ArrowLeft") seekRow(st.row - 1);
    });
    window.addEventListener("resize", () => { resize(); fit(); draw(); });
    window.addEventListener("hashchange", () => { setPlaying(false); fromHash(); });
  }

  function fromHash() { // #segment=K (counted from 1, as shown) or #row=R (from 0)
    const m = /(segment|row)=(\d+)/.exec(location.hash);
    if (!m) return seekRow(0);
    return m[1] === "segment" ? seekSegment(Number(m[2]) - 1) : seekRow(Number(m[2]));
  }

  buildPanel();
  bind();
  resize();
  fit();
  fromHash();
  window.lampViewer = {
    seekRow, seekSegment, play: () => setPlaying(true), pause: () => setPlaying(false),
    zoom, fit: () => { fit(); draw(); }, toScreen, segmentOfRow,
    get row() { return st.row; },
  };
})();
