// LAMP live view (lamp serve): draws the world as it moves, from the service's server-sent
// events (/events: "world" and "tasks"), and posts tasks (POST /tasks). The scene (shapes,
// colours) is the JSON in #lamp-data. A ?token=T in the page's address is sent with every
// request. What is shown is mirrored in #state (data-time, data-robots, data-objects,
// data-tasks, data-version) after every draw.
(function () {
  "use strict";
  const D = JSON.parse(document.getElementById("lamp-data").textContent);
  const $ = (id) => document.getElementById(id);
  const canvas = $("view"), ctx = canvas.getContext("2d");
  const token = new URLSearchParams(location.search).get("token");
  const withToken = (path) => (token ? path + "?token=" + encodeURIComponent(token) : path);
  const live = { time: 0, robots: D.robots, objects: D.objects.map((o) => o.start),
                 tasks: [], stopped: false, version: 0, pick: null };
  const st = { scale: 1, ox: 0, oy: 0 };

  // ------------------------------------------------------------------- view
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
    st.ox = cx - (cx - st.ox) * f; st.oy = cy - (cy - st.oy) * f; st.scale *= f;
    draw();
  }
  const sx = (x) => st.ox + st.scale * x;
  const sy = (y) => st.oy - st.scale * y;
  const toWorld = (X, Y) => [(X - st.ox) / st.scale, (st.oy - Y) / st.scale];

  // ------------------------------------------------------------------ shapes
  function placed(outline, x, y, th) {
    const c = Math.cos(th), s = Math.sin(th);
    return outline.map(([px, py]) => [x + c * px - s * py, y + s * px + c * py]);
  }
  function shapeAt(o, pose) {
    ctx.beginPath();
    if (o.circle !== undefined) {
      ctx.arc(sx(pose[0]), sy(pose[1]), Math.max(o.circle * st.scale, 0.5), 0, 2 * Math.PI);
      return;
    }
    placed(o.outline, pose[0], pose[1], pose[2]).forEach(([x, y], i) =>
      (i ? ctx.lineTo(sx(x), sy(y)) : ctx.moveTo(sx(x), sy(y))));
    ctx.closePath();
  }

  // ------------------------------------------------------------------- draw
  function draw() {
    const C = D.colors, [W, H] = D.workspace, R = D.robot_radius;
    ctx.setTransform(view.dpr, 0, 0, view.dpr, 0, 0);
    ctx.fillStyle = "#eef0f3"; ctx.fillRect(0, 0, view.w, view.h);
    ctx.fillStyle = "#ffffff"; ctx.fillRect(sx(0), sy(H), W * st.scale, H * st.scale);
    ctx.lineJoin = "round"; ctx.lineCap = "round";
    ctx.fillStyle = C.obstacle;
    for (const o of D.obstacles) { shapeAt(o, o.at || [0, 0, 0]); ctx.fill(); }
    ctx.strokeStyle = "#000"; ctx.lineWidth = 1.5;
    ctx.strokeRect(sx(0), sy(H), W * st.scale, H * st.scale);
    ctx.font = "11px system-ui, sans-serif";
    const shownGoals = new Map(); // per object: its active task and its next queued one
    for (const t of live.tasks) {
      if (t.status !== "queued" && t.status !== "active") continue;
      const mine = shownGoals.get(t.object) || [];
      if (mine.length < 2 && !mine.some((m) => m.status === t.status)) mine.push(t);
      shownGoals.set(t.object, mine);
    }
    for (const t of [...shownGoals.values()].flat()) { // the goals still to reach
      const o = D.objects[t.object];
      ctx.setLineDash(t.status === "active" ? [] : [5, 4]);
      ctx.strokeStyle = C.goal; ctx.lineWidth = t.status === "active" ? 2.2 : 1.2;
      shapeAt(o, t.goal); ctx.stroke();
      ctx.setLineDash([]);
      ctx.fillStyle = C.goal; ctx.fillText("#" + t.id, sx(t.goal[0]) + 3, sy(t.goal[1]) - 3);
    }
    if (live.pick) { // the goal being entered in the form
      const k = Number($("f-object").value) || 0, th = Number($("f-theta").value) || 0;
      ctx.setLineDash([2, 3]); ctx.strokeStyle = "#000"; ctx.lineWidth = 1;
      shapeAt(D.objects[k], [live.pick[0], live.pick[1], th]); ctx.stroke(); ctx.setLineDash([]);
    }
    D.objects.forEach((o, k) => {
      const p = live.objects[k];
      ctx.globalAlpha = 0.85; ctx.fillStyle = o.color; shapeAt(o, p); ctx.fill();
      ctx.globalAlpha = 1; ctx.strokeStyle = "#000"; ctx.lineWidth = 0.8; ctx.stroke();
      ctx.beginPath(); ctx.moveTo(sx(p[0]), sy(p[1]));
      ctx.lineTo(sx(p[0] + o.tick * Math.cos(p[2])), sy(p[1] + o.tick * Math.sin(p[2])));
      ctx.lineWidth = 1.2; ctx.stroke();
    });
    const rPx = Math.max(R * st.scale, D.min_robot_px);
    for (const [x, y] of live.robots) {
      ctx.beginPath(); ctx.arc(sx(x), sy(y), rPx, 0, 2 * Math.PI);
      ctx.fillStyle = C.robot; ctx.fill(); ctx.strokeStyle = "#fff"; ctx.lineWidth = 0.8; ctx.stroke();
    }
    $("clock").textContent = "t = " + live.time.toFixed(2) + " s" + (live.stopped ? "  (stopped)" : "");
    const out = $("state");
    out.dataset.time = String(live.time);
    out.dataset.robots = JSON.stringify(live.robots);
    out.dataset.objects = JSON.stringify(live.objects);
    out.dataset.tasks = JSON.stringify(live.tasks.map((t) => [t.id, t.status]));
    out.dataset.version = String(live.version);
    out.dataset.view = JSON.stringify({ scale: st.scale, ox: st.ox, oy: st.oy });
  }

  // ------------------------------------------------------------------- panel
  function fmt(v, digits) { return v === null || v === undefined ? "-" : Number(v).toFixed(digits); }
  function showTasks() {
    const body = document.querySelector("#tasks tbody");
    const rows = live.tasks.slice().reverse(); // newest first
    body.replaceChildren(...rows.map((t) => {
      const tr = document.createElement("tr");
      tr.id = "task-" + t.id;
      const cells = [t.id, t.object, t.goal.map((v) => fmt(v, 2)).join(", "), t.status,
        fmt(t.release_s, 1), fmt(t.done_s, 1)];
      cells.forEach((c, j) => {
        const td = document.createElement("td"); td.textContent = String(c);
        if (j === 3) { td.className = t.status; if (t.reason) td.title = t.reason; }
        tr.appendChild(td);
      });
      return tr;
    }));
    const n = (s) => live.tasks.filter((t) => t.status === s).length;
    $("counts").textContent = live.tasks.length + " tasks: " + n("queued") + " queued, " +
      n("active") + " active, " + n("done") + " done, " + n("failed") + " failed";
  }
  function say(text, ok) { const m = $("message"); m.textContent = text; m.className = ok ? "ok" : "error"; }

  // ------------------------------------------------------------------ the service
  function connect() {
    const es = new EventSource(withToken("events"));
    es.addEventListener("open", () => { $("link").textContent = "live"; $("link").className = "up"; });
    es.addEventListener("error", () => { // the stream ended: after a stop, for good
      $("link").textContent = live.stopped ? "stopped" : "reconnecting";
      $("link").className = "down";
      if (live.stopped) es.close();
    });
    es.addEventListener("world", (e) => {
      const w = JSON.parse(e.data);
      live.time = w.time_s; live.robots = w.robots; live.objects = w.objects;
      live.stopped = w.stopped; live.version += 1;
      draw();
    });
    es.addEventListener("tasks", (e) => { live.tasks = JSON.parse(e.data); showTasks(); draw(); });
  }
  async function post(ev) {
    ev.preventDefault();
    const body = { object: Number($("f-object").value),
                   goal: ["f-x", "f-y", "f-theta"].map((id) => Number($(id).value)) };
    const headers = { "Content-Type": "application/json" };
    if (token) headers.Authorization = "Bearer " + token;
    try {
      const r = await fetch("tasks", { method: "POST", headers, body: JSON.stringify(body) });
      const d = await r.json();
      if (r.status === 201) say("task " + d.id + " queued", true);
      else say(d.detail || ("HTTP " + r.status), false);
    } catch (err) { say("the service does not answer: " + err, false); }
  }

  function bind() {
    $("title").textContent = D.title;
    D.objects.forEach((o, k) => {
      const opt = document.createElement("option"); opt.value = String(k);
      opt.textContent = String(k); opt.style.color = o.color; $("f-object").appendChild(opt);
    });
    $("post").addEventListener("submit", post);
    ["f-object", "f-theta"].forEach((id) => $(id).addEventListener("change", draw));
    canvas.addEventListener("click", (e) => {
      const r = canvas.getBoundingClientRect();
      live.pick = toWorld(e.clientX - r.left, e.clientY - r.top);
      $("f-x").value = live.pick[0].toFixed(3); $("f-y").value = live.pick[1].toFixed(3);
      draw();
    });
    canvas.addEventListener("wheel", (e) => { // zoom about the cursor, as the viewer does
      e.preventDefault();
      const r = canvas.getBoundingClientRect();
      zoom(Math.exp(-e.deltaY * 0.0015), e.clientX - r.left, e.clientY - r.top);
    }, { passive: false });
    $("zoom-in").addEventListener("click", () => zoom(1.5));
    $("zoom-out").addEventListener("click", () => zoom(1 / 1.5));
    $("fit").addEventListener("click", () => { fit(); draw(); });
    window.addEventListener("resize", () => { resize(); fit(); draw(); });
  }

  bind();
  resize();
  fit();
  draw();
  connect();
  window.lampLive = { toScreen: (x, y) => [sx(x), sy(y)], get state() { return live; } };
})();
