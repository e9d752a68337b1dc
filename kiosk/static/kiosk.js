// The kiosk page: draw or type a character, preview the drone's path, submit, follow the job.
// Plain JavaScript, no build step. Talks only to this kiosk's JSON API (same origin).
"use strict";

(() => {
  const $ = (id) => document.getElementById(id);
  const config = {
    max_strokes: 60, max_points: 5000, max_text_chars: 1, writing_area_m: [1.2, 1.2],
  };
  const state = {
    mode: "draw",
    strokes: [],        // each: array of [x, y, t, pressure] in CSS px / s, y down
    active: null,       // { pointerId, points }
    t0: null,           // timeStamp (ms) of the drawing's first point
    lastT: 0,
    pending: null,      // what the preview was made of: { text } or { strokes }
    preview: null,
    job: null,          // { job_id, token, preview }
    events: null,       // EventSource
  };

  // --- messages ---------------------------------------------------------------------------
  function say(text, good = false) {
    const box = $("message");
    box.textContent = text;
    box.classList.toggle("good", good);
    box.hidden = !text;
  }

  async function callApi(path, body) {
    let response;
    try {
      response = await fetch(path, {
        method: body === undefined ? "GET" : "POST",
        headers: body === undefined ? {} : { "Content-Type": "application/json" },
        body: body === undefined ? undefined : JSON.stringify(body),
        credentials: "same-origin",
      });
    } catch (err) {
      return { ok: false, error: { message: "No connection to the kiosk. Please check the network and try again." } };
    }
    try {
      return await response.json();
    } catch (err) {
      return { ok: false, error: { message: "Something went wrong. Please try again." } };
    }
  }

  // --- drawing pad ------------------------------------------------------------------------
  const pad = $("pad");
  const padCtx = pad.getContext("2d");

  function fitCanvas(canvas) {
    const rect = canvas.getBoundingClientRect();
    const dpr = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(rect.width * dpr));
    const h = Math.max(1, Math.round(rect.height * dpr));
    if (canvas.width !== w || canvas.height !== h) {
      canvas.width = w;
      canvas.height = h;
    }
    const ctx = canvas.getContext("2d");
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    return { ctx, w: rect.width, h: rect.height };
  }

  function drawGuides(ctx, w, h) {
    ctx.save();
    ctx.strokeStyle = "#efe6d3";
    ctx.lineWidth = 1;
    ctx.setLineDash([6, 6]);
    ctx.beginPath();
    ctx.moveTo(w / 2, 0); ctx.lineTo(w / 2, h);
    ctx.moveTo(0, h / 2); ctx.lineTo(w, h / 2);
    ctx.moveTo(0, 0); ctx.lineTo(w, h);
    ctx.moveTo(w, 0); ctx.lineTo(0, h);
    ctx.stroke();
    ctx.restore();
  }

  function strokeWidth(p) {
    return 4 + 8 * Math.min(1, Math.max(0, p || 0.5));
  }

  function drawSegment(ctx, a, b) {
    ctx.lineWidth = strokeWidth((a[3] + b[3]) / 2);
    ctx.beginPath();
    ctx.moveTo(a[0], a[1]);
    ctx.lineTo(b[0], b[1]);
    ctx.stroke();
  }

  function redrawPad() {
    const { ctx, w, h } = fitCanvas(pad);
    ctx.clearRect(0, 0, w, h);
    drawGuides(ctx, w, h);
    ctx.strokeStyle = "#14213d";
    ctx.lineCap = "round";
    ctx.lineJoin = "round";
    const all = state.active ? [...state.strokes, state.active.points] : state.strokes;
    for (const stroke of all) {
      for (let i = 1; i < stroke.length; i += 1) drawSegment(ctx, stroke[i - 1], stroke[i]);
    }
    updateControls();
  }

  function pointCount() {
    let n = state.active ? state.active.points.length : 0;
    for (const s of state.strokes) n += s.length;
    return n;
  }

  function pointFrom(event) {
    const rect = pad.getBoundingClientRect();
    if (state.t0 === null) state.t0 = event.timeStamp;
    const t = Math.max(state.lastT, (event.timeStamp - state.t0) / 1000);
    state.lastT = t;
    const pressure = event.pressure > 0 ? event.pressure : 0.5;
    return [
      Math.round((event.clientX - rect.left) * 10) / 10,
      Math.round((event.clientY - rect.top) * 10) / 10,
      Math.round(t * 1000) / 1000,
      Math.round(pressure * 1000) / 1000,
    ];
  }

  function addPoint(event) {
    const pts = state.active.points;
    const p = pointFrom(event);
    const last = pts[pts.length - 1];
    if (last && Math.hypot(p[0] - last[0], p[1] - last[1]) < 2) return;
    if (pointCount() >= config.max_points) {
      say("That is plenty of detail! Lift your finger, then preview your character.");
      return;
    }
    pts.push(p);
    if (last) {
      padCtx.strokeStyle = "#14213d";
      padCtx.lineCap = "round";
      drawSegment(padCtx, last, p);
    }
  }

  pad.addEventListener("pointerdown", (event) => {
    if (state.active || (event.pointerType === "mouse" && event.button !== 0)) return;
    if (state.strokes.length >= config.max_strokes) {
      say(`That is a lot of strokes (at most ${config.max_strokes}). Please preview or clear it.`);
      return;
    }
    event.preventDefault();
    pad.setPointerCapture(event.pointerId);
    state.active = { pointerId: event.pointerId, points: [] };
    say("");
    $("pad-hint").hidden = true;
    addPoint(event);
  });

  pad.addEventListener("pointermove", (event) => {
    if (!state.active || event.pointerId !== state.active.pointerId) return;
    event.preventDefault();
    const events = event.getCoalescedEvents ? event.getCoalescedEvents() : [];
    for (const e of events.length ? events : [event]) addPoint(e);
  });

  function endStroke(event) {
    if (!state.active || event.pointerId !== state.active.pointerId) return;
    const pts = state.active.points;
    state.active = null;
    if (pts.length === 1) {
      // A tap: keep it as a tiny dot-stroke so dots of characters survive.
      const [x, y, t, p] = pts[0];
      pts.push([x + 2, y + 2, t, p]);
    }
    if (pts.length >= 2) state.strokes.push(pts);
    redrawPad();
  }
  pad.addEventListener("pointerup", endStroke);
  pad.addEventListener("pointercancel", endStroke);
  pad.addEventListener("lostpointercapture", endStroke);

  $("undo").addEventListener("click", () => {
    state.strokes.pop();
    if (!state.strokes.length) resetDrawing();
    redrawPad();
  });
  $("clear").addEventListener("click", () => { resetDrawing(); redrawPad(); });

  function resetDrawing() {
    state.strokes = [];
    state.active = null;
    state.t0 = null;
    state.lastT = 0;
    $("pad-hint").hidden = false;
  }

  function currentSubmission() {
    if (state.mode === "type") {
      const text = $("text").value.trim();
      return text ? { text } : null;
    }
    if (!state.strokes.length) return null;
    const rect = pad.getBoundingClientRect();
    return {
      strokes: {
        units: "px",
        y_axis: "down",
        device: navigator.maxTouchPoints > 0 ? "touch screen" : "mouse",
        canvas: { width: Math.round(rect.width), height: Math.round(rect.height) },
        strokes: state.strokes,
      },
    };
  }

  function updateControls() {
    const n = state.strokes.length;
    $("undo").disabled = n === 0;
    $("clear").disabled = n === 0;
    $("stroke-count").textContent = n ? `${n} stroke${n === 1 ? "" : "s"}` : "";
    $("preview").disabled = currentSubmission() === null;
  }

  // --- tabs -------------------------------------------------------------------------------
  function setMode(mode) {
    state.mode = mode;
    $("tab-draw").setAttribute("aria-selected", String(mode === "draw"));
    $("tab-type").setAttribute("aria-selected", String(mode === "type"));
    $("draw-pane").hidden = mode !== "draw";
    $("type-pane").hidden = mode !== "type";
    say("");
    if (mode === "draw") redrawPad(); else $("text").focus();
    updateControls();
  }
  $("tab-draw").addEventListener("click", () => setMode("draw"));
  $("tab-type").addEventListener("click", () => setMode("type"));
  $("text").addEventListener("input", updateControls);
  $("text").addEventListener("keydown", (e) => {
    if (e.key === "Enter" && !e.isComposing && !$("preview").disabled) $("preview").click();
  });

  // --- planned path pictures --------------------------------------------------------------
  function drawPath(canvas, preview) {
    const { ctx, w, h } = fitCanvas(canvas);
    ctx.clearRect(0, 0, w, h);
    drawGuides(ctx, w, h);
    const [aw, ah] = preview.writing_area_m;
    const scale = Math.min(w / aw, h / ah) * 0.92;
    const map = (p) => [w / 2 + p[0] * scale, h / 2 - p[1] * scale];
    ctx.lineCap = "round";
    ctx.lineJoin = "round";
    // Runs of equal pen state as one path each, so the air moves show as dashes.
    const path = preview.path;   // [x, y, pen_down]
    let start = 0;
    while (start < path.length - 1) {
      const down = Boolean(path[start + 1][2] && path[start][2]);
      let end = start + 1;
      while (end < path.length - 1 && Boolean(path[end + 1][2] && path[end][2]) === down) end += 1;
      ctx.strokeStyle = down ? "#14213d" : "#8d99ae";
      ctx.lineWidth = down ? 6 : 1.5;
      ctx.setLineDash(down ? [] : [5, 5]);
      ctx.beginPath();
      const first = map(path[start]);
      ctx.moveTo(first[0], first[1]);
      for (let i = start + 1; i <= end; i += 1) {
        const p = map(path[i]);
        ctx.lineTo(p[0], p[1]);
      }
      ctx.stroke();
      start = end;
    }
    ctx.setLineDash([]);
    ctx.fillStyle = "#e85d04";
    for (const stroke of preview.turning_points) {
      for (const p of stroke) {
        const [x, y] = map(p);
        ctx.beginPath();
        ctx.arc(x, y, 4, 0, 2 * Math.PI);
        ctx.fill();
      }
    }
  }

  function show(section) {
    for (const id of ["compose", "confirm", "status"]) $(id).hidden = id !== section;
    window.scrollTo(0, 0);
  }

  $("preview").addEventListener("click", async () => {
    const submission = currentSubmission();
    if (!submission) return;
    $("preview").disabled = true;
    say("");
    const reply = await callApi("/api/preview", submission);
    $("preview").disabled = false;
    if (!reply.ok) { say(reply.error.message); return; }
    state.pending = submission;
    state.preview = reply.preview;
    show("confirm");
    drawPath($("preview-canvas"), reply.preview);
    const secs = Math.round(reply.preview.duration_s);
    $("preview-facts").textContent =
      `${reply.preview.turning_point_count} turning points, about ${secs} seconds of flying.`;
  });

  $("back").addEventListener("click", () => { show("compose"); redrawPad(); });

  // --- submitting and following -----------------------------------------------------------
  $("submit").addEventListener("click", async () => {
    $("submit").disabled = true;
    const reply = await callApi("/api/submit", state.pending);
    $("submit").disabled = false;
    if (!reply.ok) { say(reply.error.message); return; }
    say("");
    const title = state.pending.text ? `Your character: ${state.pending.text}` : "Your drawing";
    state.job = {
      job_id: reply.job_id, token: reply.token, preview: reply.preview || state.preview, title,
    };
    try { sessionStorage.setItem("skyquill-job", JSON.stringify(state.job)); } catch (err) { /* private mode */ }
    showJob(reply.job);
  });

  function showJob(job) {
    show("status");
    $("job-id").textContent = state.job.job_id;
    $("status-title").textContent = state.job.title;
    $("result").hidden = false;
    $("result-facts").textContent = "This is the path the drone will fly.";
    if (state.job.preview) drawPath($("result-canvas"), state.job.preview);
    render(job);
    follow(state.job.job_id, state.job.token);
  }

  function follow(jobId, token) {
    if (state.events) state.events.close();
    const url = `/api/jobs/${encodeURIComponent(jobId)}/events?token=${encodeURIComponent(token)}`;
    const events = new EventSource(url);
    state.events = events;
    events.addEventListener("job", (e) => {
      const job = JSON.parse(e.data);
      render(job);
      if (job.final) {
        events.close();
        state.events = null;
        try { sessionStorage.removeItem("skyquill-job"); } catch (err) { /* private mode */ }
      }
    });
  }

  function render(job) {
    if (!job) return;
    $("status-text").textContent = job.status_text;
    const waiting = job.state === "queued";
    $("queue-place").textContent = waiting && job.queue_position ? `${job.queue_position}` : "-";
    $("eta").textContent = waiting && job.eta_s != null
      ? (job.eta_s < 60 ? "under a minute" : `${Math.round(job.eta_s / 60)} min`) : "-";
    const bar = $("progress");
    bar.hidden = job.state !== "writing";
    bar.value = job.progress || 0;
    if (job.final && job.state !== "done") $("result").hidden = true;
    if (job.state === "done" && state.job) {
      const m = job.metrics;
      let facts = "Written!";
      if (m) {
        facts = `Written in ${Math.round(m.duration_s)} s, on average within ` +
          `${(m.rmse_pen_down_m * 100).toFixed(1)} cm of the plan.`;
        if (m.iou != null) facts += ` The ink matches the plan ${Math.round(m.iou * 100)}%.`;
      }
      $("result-facts").textContent = facts;
    }
  }

  $("again").addEventListener("click", () => {
    if (state.events) { state.events.close(); state.events = null; }
    try { sessionStorage.removeItem("skyquill-job"); } catch (err) { /* private mode */ }
    state.job = null;
    resetDrawing();
    $("text").value = "";
    show("compose");
    redrawPad();
  });

  // --- start ------------------------------------------------------------------------------
  // After a reload: follow the job this tab submitted, if the kiosk still knows it.
  async function resume() {
    let saved = null;
    try { saved = JSON.parse(sessionStorage.getItem("skyquill-job") || "null"); } catch (err) { return; }
    if (!saved || !saved.job_id || !saved.token) return;
    const reply = await callApi(
      `/api/jobs/${encodeURIComponent(saved.job_id)}?token=${encodeURIComponent(saved.token)}`);
    if (!reply.ok) {
      try { sessionStorage.removeItem("skyquill-job"); } catch (err) { /* private mode */ }
      return;
    }
    state.job = saved;
    showJob(reply.job);
  }

  async function start() {
    const reply = await callApi("/api/config");
    if (reply.ok) Object.assign(config, reply.config);
    if (config.max_text_chars > 1) {
      document.querySelector(".type-label").textContent =
        `A letter, a Chinese character or a short word (at most ${config.max_text_chars})`;
    }
    new ResizeObserver(() => { if (!$("compose").hidden) redrawPad(); }).observe(pad);
    redrawPad();
    resume();
    document.body.dataset.ready = "1";
  }
  start();
})();
