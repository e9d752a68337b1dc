// The crew's page: pair this phone once with the operator's code, then follow the boards
// waiting for a fresh sheet and the vehicles waiting for a battery, and confirm each with one
// tap. Everything shown is text (textContent through the catalogues), never markup.
"use strict";

(() => {
  const I = window.SkyquillI18n;
  const $ = (id) => document.getElementById(id);
  const STALE_AFTER_MS = 2500;  // the kiosk sends a frame every 0.5 s
  const ERRORS = {
    bad_state: "err_bad_state",
    unavailable: "err_unavailable",
    bad_code: "err_bad_code",
    not_paired: "err_not_paired",
    rate_limited: "err_rate_limited",
    forbidden: "err_forbidden",
  };
  const state = { events: null, lastLive: 0, serverStale: false, watchdog: null, tasks: [] };
  const pending = new Set();  // confirmations sent and not yet answered

  function say(key, args, good = false) {
    const box = $("message");
    box.hidden = !key;
    box.classList.toggle("good", good);
    if (key) I.set(box, key, args); else { box.textContent = ""; delete box.dataset.i18n; }
  }

  function sayError(error) {
    const code = (error && error.code) || "internal";
    const secs = Math.max(1, Math.round((error && error.retry_after_s) || 60));
    say(ERRORS[code] || "err_internal", { secs });
    if (code === "not_paired") showPair();
  }

  async function post(url, body) {
    try {
      const reply = await fetch(url, {
        method: "POST",
        credentials: "same-origin",
        headers: { "Content-Type": "application/json" },
        body: JSON.stringify(body),
      });
      return await reply.json();
    } catch (err) {
      return { ok: false, error: { code: "unavailable" } };
    }
  }

  // --- pairing ------------------------------------------------------------------------------
  function showPair() {
    stopFollowing();
    $("work").hidden = true;
    $("who").hidden = true;
    $("stale").hidden = true;
    $("pair").hidden = false;
  }

  function paired(name) {
    $("pair").hidden = true;
    $("work").hidden = false;
    I.set($("who"), "paired_as", { name });
    $("who").hidden = false;
    follow();
  }

  async function pair(event) {
    event.preventDefault();
    const button = $("pair-button");
    button.disabled = true;
    const data = await post("/crew/api/pair", { code: $("code").value });
    button.disabled = false;
    if (!data.ok) { sayError(data.error); return; }
    $("code").value = "";
    say("");
    paired(data.name);
  }

  async function whoAmI() {
    try {
      const reply = await fetch("/crew/api/me", { credentials: "same-origin" });
      if (reply.status === 401) { showPair(); return; }
      const data = await reply.json();
      if (data.ok) paired(data.name);
    } catch (err) { /* the kiosk is away: the watchdog says so */ }
  }

  // --- the tasks ----------------------------------------------------------------------------
  function what(task) {
    if (task.command === "fresh_sheet") {
      return task.place === null
        ? ["board_plain", { board: task.target }]
        : ["board_named", { board: task.target, place: task.place }];
    }
    return task.place === null
      ? ["vehicle_plain", { vehicle: task.target }]
      : ["vehicle_named", { vehicle: task.target, place: task.place }];
  }

  function item(task, index) {
    const li = document.createElement("li");
    const label = document.createElement("span");
    label.className = "what";
    label.id = `task-${index}`;
    I.set(label, ...what(task));
    if (task.percent !== null) {
      const detail = document.createElement("span");
      detail.className = "detail";
      I.set(detail, "percent_left", { percent: task.percent });
      label.append(detail);
    }
    const button = document.createElement("button");
    button.type = "button";
    button.dataset.command = task.command;
    button.dataset.target = task.target;
    button.setAttribute("aria-describedby", label.id);
    const key = `${task.command}:${task.target}`;
    button.disabled = task.confirmed || pending.has(key);
    const sheet = task.command === "fresh_sheet";
    I.set(button, task.confirmed ? "confirmed" : sheet ? "sheet_button" : "battery_button");
    button.addEventListener("click", () => confirm(task, key));
    li.append(label, button);
    return li;
  }

  function render(tasks) {
    state.tasks = tasks;
    for (const [list, command] of [["sheets", "fresh_sheet"], ["batteries", "battery_swapped"]]) {
      const mine = tasks.filter((t) => t.command === command);
      $(list).replaceChildren(...mine.map((t) => item(t, tasks.indexOf(t))));
      $(`${list}-none`).hidden = mine.length > 0;
    }
  }

  async function confirm(task, key) {
    if (pending.has(key)) return;
    pending.add(key);
    render(state.tasks);
    const data = await post("/crew/api/confirm", { command: task.command, target: task.target });
    pending.delete(key);
    if (data.ok) {
      const done = task.command === "fresh_sheet"
        ? ["done_sheet", { board: task.target }] : ["done_battery", { vehicle: task.target }];
      say(...done, true);
    } else {
      sayError(data.error);
    }
    render(state.tasks);
  }

  // --- live updates -------------------------------------------------------------------------
  function follow() {
    stopFollowing();
    const events = new EventSource("/crew/api/events");
    state.events = events;
    state.lastLive = Date.now();
    events.addEventListener("tasks", (e) => {
      state.lastLive = Date.now();
      render(JSON.parse(e.data).tasks);
    });
    events.addEventListener("live", (e) => {
      state.lastLive = Date.now();
      state.serverStale = Boolean(JSON.parse(e.data).stale);
      checkStale();
    });
    events.addEventListener("error", () => whoAmI());  // unpaired meanwhile: ask for a code
    state.watchdog = setInterval(checkStale, 500);
  }

  function stopFollowing() {
    if (state.events) state.events.close();
    if (state.watchdog) clearInterval(state.watchdog);
    state.events = null;
    state.watchdog = null;
  }

  function checkStale() {
    const lost = Date.now() - state.lastLive > STALE_AFTER_MS;
    const key = lost ? "stale" : state.serverStale ? "show_slow" : null;
    const box = $("stale");
    if (key && box.dataset.i18n !== key) I.set(box, key);
    box.hidden = !key;
  }

  async function start() {
    await I.load("/static/i18n/crew");
    $("pair").addEventListener("submit", pair);
    await whoAmI();
    document.body.dataset.ready = "1";
  }

  start();
})();
