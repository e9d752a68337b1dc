// A phrase written together: typed characters, one per board, each by its own drone, on boards
// side by side in reading order. Its tab, its preview (the row of boards), and its one ticket:
// the phrase summed up and each character (waiting, being written by drone k, written, failed
// and written again alone); a character written shows on its board the ink its drone left, in
// place of the plan. Drones are named by their board's place from the left. Whatever the
// visitor typed is set as text, never markup.
"use strict";

window.SkyquillPhrase = (() => {
  const $ = (id) => document.getElementById(id);
  const { set: word } = window.SkyquillI18n;
  const { fitCanvas, drawGuides, drawPath, drawInk } = window.SkyquillPictures;
  let row = 0;          // boards in the show's row (the longest phrase)
  let drawnRow = "";    // what the status row shows now (redrawn only when it changes)

  // The tab shows when the show has at least two boards in its row.
  function setup(config) {
    row = config.max_phrase_chars || 0;
    $("tab-phrase").hidden = row < 2;
    if (row >= 2) word($("phrase-label"), "phrase_label", { n: row });
  }

  function submission() {
    const text = $("phrase-text").value.trim();
    return text ? { text, phrase: true } : null;
  }

  // One picture per board of the row: on a character's board the ink its drone left once
  // written (``inks``, in the frame of ``areaM``), else its planned path; the others empty.
  function drawRow(box, characters, boards, labels, inks = [], areaM = null) {
    box.textContent = "";
    const count = Math.max(row, ...boards.filter(Boolean));
    box.style.setProperty("--boards", String(count));
    for (let b = 1; b <= count; b += 1) {
      const figure = document.createElement("figure");
      const canvas = document.createElement("canvas");
      canvas.className = "phrase-board";
      const caption = document.createElement("figcaption");
      figure.append(canvas, caption);
      box.append(figure);
      const i = boards.indexOf(b);
      if (i >= 0) {
        figure.classList.add("used");
        canvas.setAttribute("role", "img");
        word(canvas, "phrase_board_label", { n: b, text: labels[i] || "" }, "aria-label");
        word(caption, "phrase_board_char", { n: b, text: labels[i] || "" });
      } else {
        word(caption, "phrase_board", { n: b });
      }
      if (i >= 0 && inks[i]) {
        figure.classList.add("written");
        drawInk(canvas, inks[i], areaM);
      } else if (i >= 0 && characters[i]) drawPath(canvas, characters[i]);
      else { const { ctx, w, h } = fitCanvas(canvas); drawGuides(ctx, w, h); }
    }
  }

  const fromLeft = (n) => Array.from({ length: n }, (_, i) => i + 1);

  // The preview: the characters on adjacent boards from the left (the boards they get are the
  // first free ones side by side), and what the visitor should know.
  function showPreview(preview) {
    $("preview-canvas").hidden = true;
    $("phrase-row").hidden = false;
    const chars = preview.characters;
    drawRow($("phrase-row"), chars, fromLeft(chars.length), chars.map((c) => c.label));
    word($("preview-facts"), "phrase_facts", {
      n: chars.length, secs: Math.round(preview.duration_s),
    });
  }

  function hidePreview() {
    $("preview-canvas").hidden = false;
    $("phrase-row").hidden = true;
  }

  // The sentence about the whole phrase: [key, args].
  function words(job) {
    const p = job.phrase;
    const n = p.size;
    const said = { reason: job.reason };
    switch (job.state) {
      case "awaiting_approval": return ["ph_approval", {}];
      case "queued":
        if (job.show_paused) return ["ph_paused", {}];
        return ["ph_waits", { n, eta: window.SkyquillStatus.duration(job.eta_s) }];
      case "assigned": case "writing": return ["ph_writing", { n, done: p.written }];
      case "done":
        return ["ph_done", { n, first: p.boards[0], last: p.boards[p.boards.length - 1] }];
      case "rejected": return job.reason ? ["ph_rejected_reason", said] : ["ph_rejected", {}];
      case "cancelled": return job.reason ? ["ph_cancelled_reason", said] : ["ph_cancelled", {}];
      default: {
        // a character that could not be written before the phrase began ended it whole
        const cause = p.characters.find((c) => c.state === "failed" && !c.with_phrase);
        if (p.written === 0 && cause && p.characters.some((c) => c.with_phrase)) {
          return ["ph_failed_whole", { char: cause.label }];
        }
        return ["ph_failed", { n, done: p.written }];
      }
    }
  }

  // The words of one character: [key, args].
  function characterWords(c) {
    const drone = { key: "drone_named", args: { n: c.board } };
    const pct = Math.round(100 * Math.max(0, Math.min(1, c.progress || 0)));
    switch (c.state) {
      case "submitted": case "awaiting_approval": return ["ph_c_approval", {}];
      case "queued": return [c.again ? "ph_c_again" : "ph_c_waiting", {}];
      case "assigned": return c.board ? ["ph_c_assigned", { drone }] : ["ph_c_waiting", {}];
      case "writing":
        return c.board ? [c.again ? "ph_c_rewriting" : "ph_c_writing", { drone, pct }]
          : ["ph_c_waiting", {}];
      case "done": return c.board ? ["ph_c_done", { drone }] : ["ph_c_done_any", {}];
      case "failed": return [c.with_phrase ? "ph_c_with_phrase" : "ph_c_failed", {}];
      case "cancelled": return ["ph_c_cancelled", {}];
      case "rejected": return ["ph_c_rejected", {}];
      default: return ["ph_c_checking", {}];
    }
  }

  // The ticket of a phrase: its row of boards (the plan, then each character's ink as it is
  // written) and the list of its characters.
  function render(job, preview) {
    $("phrase-status").hidden = false;
    const chars = job.phrase.characters;
    const boards = chars.map((c) => c.board);
    const placed = boards.every(Boolean) ? boards : fromLeft(chars.length);
    const labels = chars.map((c) => c.label);
    const inks = chars.map((c) => c.written || null);
    const inked = inks.map((ink) => (ink ? ink.bits : null));
    const key = JSON.stringify([placed, labels, inked, document.documentElement.lang]);
    if (key !== drawnRow) {
      drawnRow = key;
      const plans = preview ? preview.characters : [];
      const area = preview ? preview.writing_area_m : null;
      drawRow($("phrase-status-row"), plans, placed, labels, inks, area);
    }
    const list = $("phrase-chars");
    list.textContent = "";
    for (const c of chars) {
      const li = document.createElement("li");
      li.dataset.state = c.state;
      const label = document.createElement("span");
      label.className = "ph-label";
      label.textContent = c.label;  // the visitor's character, as text
      const said = document.createElement("span");
      said.className = "ph-state";
      word(said, ...characterWords(c));
      li.append(label, said);
      list.append(li);
    }
  }

  function hide() {
    $("phrase-status").hidden = true;
    drawnRow = "";
  }

  return { setup, submission, showPreview, hidePreview, words, render, hide };
})();
