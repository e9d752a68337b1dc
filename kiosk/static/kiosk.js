// The kiosk page: draw or type a character, preview the drone's path, submit, follow the job.
// Plain JavaScript, no build step. Talks only to this kiosk's JSON API (same origin).
"use strict";

(() => {
  const $ = (id) => document.getElementById(id);
  const { t, set: word } = window.SkyquillI18n;
  const { fitCanvas, drawGuides, drawPath, animatePath, drawInk } = window.SkyquillPictures;
  const phrase = window.SkyquillPhrase;
  const config = {
    max_strokes: 60, max_points: 5000, max_text_chars: 1, writing_area_m: [1.2, 1.2],
    idle_reset_s: 60, width_range_m: null,
  };
  const state = {
    mode: "draw",
    strokes: [],        // each: array of [x, y, t, pressure] in CSS px / s, y down
    active: null,       // { pointerId, points }
    t0: null,           // timeStamp (ms) of the drawing's first point
    lastT: 0,
    pending: null,      // what the preview was made of: { text } or { strokes }
    preview: null,
    job: null,          // { ticket, token, code, preview, text }: followed by its ticket
    lastJob: null,      // the latest view of that job (reworded after a language switch)
    events: null,       // EventSource
    lastLive: 0,        // Date.now() of the last frame of the status stream
    serverStale: false, // the kiosk says the orchestrator's news stopped (the show is slow)
    watchdog: null,     // interval that notices a silent stream
  };
  const STALE_AFTER_MS = 2500;   // the kiosk sends a frame every 0.5 s
  const SAVED = "skyquill-tickets";  // localStorage: my characters, newest first
  const CURRENT = "skyquill-current";

  // --- messages (a catalogue key and its arguments; "" clears) ------------------------------
  function say(key, args) {
    const box = $("message");
    box.hidden = !key;
    if (key) word(box, key, args); else { box.textContent = ""; delete box.dataset.i18n; }
  }

  // A refusal of the API, worded from its stable code in the visitor's language.
  function sayError(error, context = {}) {
    say(...errorWords(error, context));
  }

  function errorWords(error, context = {}) {
    const code = (error && error.code) || "internal";
    const args = {
      n: code === "too_many_strokes" ? config.max_strokes
        : code.startsWith("phrase_") ? config.max_phrase_chars : config.max_text_chars,
      secs: Math.max(1, Math.round((error && error.retry_after_s) || 60)),
      limit: Math.round(config.max_flight_s || 90),
      flight: Math.round((error && error.flight_s) || 0),
      char: context.text || "",
    };
    if (code === "text_too_long" && config.max_text_chars === 1) return ["err_text_one_char", args];
    if (code === "unknown_job" && context.byCode) return ["err_unknown_code", args];
    if (code === "no_glyph" && !context.text) return ["err_unplannable", args];
    if (code === "paused" || code === "storage_full") return ["err_queue_full", args];
    if (code === "too_long" && args.flight) return ["err_too_long_s", args];
    const key = `err_${code}`;
    return [t(key) === key ? "err_refused" : key, args];
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
      return { ok: false, error: { code: "no_connection" } };
    }
    try {
      return await response.json();
    } catch (err) {
      return { ok: false, error: { code: "internal" } };
    }
  }

  // --- drawing pad ------------------------------------------------------------------------
  const pad = $("pad");
  const padCtx = pad.getContext("2d");

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
      say("err_plenty");
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
      say("err_many_strokes", { n: config.max_strokes });
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
    if (state.mode === "phrase") return phrase.submission();
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
        strokes: window.SkyquillWidths.withWidths(state.strokes, config.width_range_m),
      },
    };
  }

  function updateControls() {
    const n = state.strokes.length;
    $("undo").disabled = n === 0;
    $("clear").disabled = n === 0;
    if (n) word($("stroke-count"), "strokes", { n }); else clearWords($("stroke-count"));
    const empty = currentSubmission() === null;
    $("preview").disabled = empty;
    $("preview-why").hidden = !empty;  // a disabled button says why
    word($("preview-why"), `why_${state.mode}`);
  }

  // --- tabs (ARIA tabs pattern: one tab stop, arrow keys move between tabs) -----------------
  const tabs = [["draw", $("tab-draw")], ["type", $("tab-type")], ["phrase", $("tab-phrase")]];
  function setMode(mode, fromKeyboard = false) {
    state.mode = mode;
    for (const [name, tab] of tabs) {
      tab.setAttribute("aria-selected", String(name === mode));
      tab.tabIndex = name === mode ? 0 : -1;
    }
    $("draw-pane").hidden = mode !== "draw";
    $("type-pane").hidden = mode !== "type";
    $("phrase-pane").hidden = mode !== "phrase";
    say("");
    if (mode === "draw") redrawPad();
    else if (!fromKeyboard) $(mode === "type" ? "text" : "phrase-text").focus();
    updateControls();
  }
  for (const [name, tab] of tabs) {
    tab.addEventListener("click", () => setMode(name));
    tab.addEventListener("keydown", (e) => {
      const shown = tabs.filter(([, t]) => !t.hidden);
      const i = shown.findIndex(([n]) => n === name);
      const next = { ArrowRight: i + 1, ArrowLeft: i - 1, Home: 0, End: shown.length - 1 }[e.key];
      if (next === undefined) return;
      e.preventDefault();
      const [mode, target] = shown[(next + shown.length) % shown.length];
      setMode(mode, true);
      target.focus();
    });
  }
  for (const input of [$("text"), $("phrase-text")]) {
    input.addEventListener("input", updateControls);
    input.addEventListener("keydown", (e) => {
      if (e.key === "Enter" && !e.isComposing && !$("preview").disabled) $("preview").click();
    });
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
    if (!reply.ok) { sayError(reply.error, submission); return; }
    state.pending = submission;
    state.preview = reply.preview;
    show("confirm");
    if (reply.preview.phrase) { phrase.showPreview(reply.preview); $("confirm-title").focus(); return; }
    phrase.hidePreview();
    animatePath($("preview-canvas"), reply.preview);
    const facts = {
      n: reply.preview.stroke_count,
      turns: reply.preview.turning_point_count,
      secs: Math.round(reply.preview.duration_s),
    };
    word($("preview-facts"), "preview_facts", facts);
    showWidths(reply.preview);
    // the text alternative: what a sighted visitor reads off the picture
    word($("preview-canvas"), "describe_path", facts, "aria-label");
    $("confirm-title").focus();
  });

  // Where the kind writes with a width: the planned range (leaving out the pen's touching on
  // and lifting off, thinner than it writes), and how many were clamped.
  function showWidths(preview) {
    const box = $("preview-widths");
    word($("legend-ink"), preview.widths ? "legend_ink_width" : "legend_ink");
    const [low] = preview.width_range_m || [0];
    const widths = preview.widths
      ? preview.path.filter((p) => p[2] && p[3] >= low - 1e-6).map((p) => p[3]) : [];
    box.hidden = !widths.length;
    if (!widths.length) return;
    const mm = (w) => (w * 1000).toFixed(1);
    if (preview.widths_clamped > 0) {
      word(box, "warn_widths_clamped", { n: preview.widths_clamped });
    } else {
      word(box, "preview_widths", { low: mm(Math.min(...widths)), high: mm(Math.max(...widths)) });
    }
  }

  $("back").addEventListener("click", () => { show("compose"); redrawPad(); });

  // --- submitting and following -----------------------------------------------------------
  $("submit").addEventListener("click", async () => {
    $("submit").disabled = true;
    const reply = await callApi("/api/submit", state.pending);
    $("submit").disabled = false;
    if (!reply.ok) { sayError(reply.error, state.pending); return; }
    say("");
    state.job = {
      ticket: reply.ticket, token: reply.token, code: reply.code,
      preview: reply.preview || state.preview, text: state.pending.text || null,
      phrase: Boolean(state.pending.phrase),
    };
    saveTicket(state.job);
    showJob(reply.job);
    $("status-title").focus();
  });

  // --- my characters, kept in this browser (survive a new tab and a closed browser) ----------
  function savedTickets() {
    try { return JSON.parse(localStorage.getItem(SAVED) || "[]"); } catch (err) { return []; }
  }

  function saveTicket(job) {
    const list = [job, ...savedTickets().filter((t) => t.ticket !== job.ticket)].slice(0, 20);
    try {
      localStorage.setItem(SAVED, JSON.stringify(list));
      localStorage.setItem(CURRENT, job.ticket);
    } catch (err) { /* private mode: this tab still follows it */ }
    renderSaved();
  }

  function renderSaved() {
    const list = savedTickets();
    const box = $("mine");
    box.hidden = list.length === 0;
    const ul = $("mine-list");
    ul.textContent = "";
    for (const t of list) {
      const li = document.createElement("li");
      const button = document.createElement("button");
      button.type = "button";
      button.className = "link";
      titleOf(button, t);  // text, never markup
      button.addEventListener("click", () => resumeTicket(t));
      li.append(button);
      ul.append(li);
    }
  }

  function showJob(job) {
    show("status");
    titleOf($("status-title"), state.job);
    showCode(state.job);
    const single = state.job.preview && !state.job.preview.phrase;
    $("result").hidden = !single;
    $("written-figure").hidden = true;
    $("planned-caption").hidden = true;
    word($("result-facts"), "plan_note");
    phrase.hide();
    if (single) drawPath($("result-canvas"), state.job.preview);
    render(job);
    follow(state.job.ticket, state.job.token);
  }

  // The ticket's one identifier on screen, its short code, and its QR code: the same ticket on
  // another device (/t/<code>).
  function showCode(job) {
    $("elsewhere").hidden = !job.code;
    $("code").textContent = job.code ? `${job.code.slice(0, 4)}-${job.code.slice(4)}` : "-";
    if (!job.code) return;
    const link = `${location.origin}/t/${job.code}`;
    $("code-link").textContent = link;
    $("qr").src = `/api/jobs/${encodeURIComponent(job.ticket)}/qr.svg?token=${encodeURIComponent(job.token)}`;
    word($("qr"), "qr_alt", { link }, "alt");
  }

  function stopFollowing() {
    if (state.events) { state.events.close(); state.events = null; }
    if (state.watchdog) { clearInterval(state.watchdog); state.watchdog = null; }
    $("stale").hidden = true;
    delete $("stale").dataset.i18n;
  }

  function follow(ticket, token) {
    stopFollowing();
    const url = `/api/jobs/${encodeURIComponent(ticket)}/events?token=${encodeURIComponent(token)}`;
    const events = new EventSource(url);
    state.events = events;
    state.lastLive = Date.now();
    state.serverStale = false;
    events.addEventListener("job", (e) => {
      state.lastLive = Date.now();
      const job = JSON.parse(e.data);
      render(job);
      if (job.final) stopFollowing();
    });
    events.addEventListener("live", (e) => {
      state.lastLive = Date.now();
      state.serverStale = Boolean(JSON.parse(e.data).stale);
      checkStale();
    });
    state.watchdog = setInterval(checkStale, 500);
  }

  // Old news must not look current: say so as soon as the stream or the show goes quiet. A
  // silent stream is a lost connection to this kiosk; a kiosk that says the orchestrator's news
  // stopped is reachable: only the show is slow to answer.
  function checkStale() {
    const lost = Date.now() - state.lastLive > STALE_AFTER_MS;
    const key = lost ? "stale" : state.serverStale ? "show_slow" : null;
    const box = $("stale");
    if (key && box.dataset.i18n !== key) word(box, key);
    box.hidden = !key;
  }

  function render(job) {
    if (!job) return;
    state.lastJob = job;
    const said = job.phrase ? phrase.words(job) : window.SkyquillStatus.words(job, errorWords);
    word($("status-text"), ...said);
    const waiting = job.state === "queued";
    $("queue-place").textContent = waiting && job.queue_position ? `${job.queue_position}` : "-";
    if (waiting && job.eta_s != null) {
      if (job.eta_s < 60) word($("eta"), "eta_soon");
      else word($("eta"), "eta_minutes", { n: Math.round(job.eta_s / 60) });
    } else clearWords($("eta"), "-");
    const bar = $("progress");
    bar.hidden = job.state !== "writing";
    bar.value = job.progress || 0;
    if (job.phrase) { phrase.render(job, state.job && state.job.preview); return; }
    // a character written, well or out of the show's bounds: its pictures, never hidden
    const written = job.state === "done" || (job.state === "failed" && job.metrics);
    if (written && state.job) showResult(job);
    else if (job.final) $("result").hidden = true;
  }

  // The written character: the plan and the ink the drone left, with words a visitor reads.
  function showResult(job) {
    const written = job.metrics && job.metrics.written;
    const area = state.job.preview ? state.job.preview.writing_area_m : null;
    $("result").hidden = false;
    $("planned-caption").hidden = !written;
    $("written-figure").hidden = !written;
    if (written) drawInk($("written-canvas"), written, area);
    const facts = window.SkyquillStatus.resultWords(job);
    if (!written) facts.push(["no_written", {}]);
    const box = $("result-facts");
    const gap = document.documentElement.lang.startsWith("zh") ? "" : " ";  // no spaces in Chinese
    box.textContent = "";
    for (const [key, args] of facts) {
      const span = document.createElement("span");
      word(span, key, args);
      box.append(span, gap);
    }
  }

  function clearWords(el, text = "") {
    delete el.dataset.i18n;
    delete el.dataset.i18nArgs;
    el.textContent = text;
  }

  function titleOf(el, job) {
    if (job.phrase) word(el, "title_phrase", { text: job.text });
    else if (job.text) word(el, "title_text", { text: job.text }); else word(el, "title_drawing");
  }

  $("again").addEventListener("click", () => {
    stopFollowing();
    try { localStorage.removeItem(CURRENT); } catch (err) { /* private mode */ }
    state.job = null;
    renderSaved();
    resetDrawing();
    $("text").value = $("phrase-text").value = "";
    show("compose");
    redrawPad();
  });

  // --- start ------------------------------------------------------------------------------
  // After a reload, in a new tab or a reopened browser: follow the character being followed.
  async function resumeTicket(saved) {
    if (!saved || !saved.ticket || !saved.token) return;
    const reply = await callApi(
      `/api/jobs/${encodeURIComponent(saved.ticket)}?token=${encodeURIComponent(saved.token)}`);
    if (!reply.ok) {
      const list = savedTickets().filter((t) => t.ticket !== saved.ticket);
      try { localStorage.setItem(SAVED, JSON.stringify(list)); } catch (err) { /* private mode */ }
      renderSaved();
      return;
    }
    state.job = { ...saved };
    try { localStorage.setItem(CURRENT, saved.ticket); } catch (err) { /* private mode */ }
    showJob(reply.job);
  }

  // Opened from a short code (/t/<code>, typed or scanned): follow that ticket here too.
  async function openCode(code) {
    const reply = await callApi(`/api/t/${encodeURIComponent(code)}`);
    history.replaceState(null, "", "/");
    if (!reply.ok) { sayError(reply.error, { byCode: true }); return; }
    state.job = {
      ticket: reply.ticket, token: reply.token, code: reply.code,
      preview: reply.preview, text: reply.label.startsWith("drawing (") ? null : reply.label,
      phrase: Boolean(reply.preview && reply.preview.phrase),
    };
    saveTicket(state.job);
    showJob(reply.job);
  }

  function resume() {
    const opened = location.pathname.match(/^\/t\/([A-Za-z0-9-]{4,16})$/);
    if (opened) { openCode(opened[1]); return; }
    let current = null;
    try { current = localStorage.getItem(CURRENT); } catch (err) { return; }
    resumeTicket(savedTickets().find((t) => t.ticket === current));
  }

  // --- shared tablets: back to the start after a while without a touch ---------------------
  let idleTimer = null;
  function touched() {
    clearTimeout(idleTimer);
    if (config.idle_reset_s > 0) idleTimer = setTimeout(idleReset, config.idle_reset_s * 1000);
  }
  // A character still on its way stays on screen (its visitor is watching it); a finished one,
  // a drawing or a preview left alone goes, and the next visitor starts afresh.
  function idleReset() {
    const watching = !$("status").hidden && state.events !== null;
    if (watching) { touched(); return; }
    stopFollowing();
    try { localStorage.removeItem(CURRENT); } catch (err) { /* private mode */ }
    state.job = null;
    resetDrawing();
    $("text").value = $("phrase-text").value = "";
    setMode("draw", true);
    show("compose");
    redrawPad();
    touched();
  }
  for (const name of ["pointerdown", "keydown", "input", "wheel"]) {
    document.addEventListener(name, touched, { capture: true, passive: true });
  }

  async function start() {
    const [reply] = await Promise.all([callApi("/api/config"), window.SkyquillI18n.load()]);
    if (reply.ok) Object.assign(config, reply.config);
    if (config.max_text_chars > 1) {
      word(document.querySelector(".type-label"), "type_label_many", { n: config.max_text_chars });
    }
    phrase.setup(config);
    // pictures are drawn, not worded: draw the finished one again after a switch (sizes move)
    window.SkyquillI18n.onChange(() => { if (state.lastJob) render(state.lastJob); });
    new ResizeObserver(() => { if (!$("compose").hidden) redrawPad(); }).observe(pad);
    redrawPad();
    renderSaved();
    touched();
    resume();
    document.body.dataset.ready = "1";
  }
  start();
})();
