// What the status page says about a job, as catalogue keys and arguments (worded in i18n.js):
// the API sends states and numbers, never sentences the page shows.
"use strict";

window.SkyquillStatus = (() => {
  const pct = (fraction) => Math.round(100 * Math.max(0, Math.min(1, fraction || 0)));

  function duration(seconds) {
    if (seconds == null || !Number.isFinite(seconds)) return { key: "dur_unknown" };
    if (seconds < 60) return { key: "dur_under" };
    const n = Math.round(seconds / 60);
    return n <= 1 ? { key: "dur_one" } : { key: "dur_many", args: { n } };
  }

  function drone(job) {
    // named for the public by its board's place from the left, never by its internal id
    return job.board ? { key: "drone_named", args: { n: job.board } } : { key: "drone_any" };
  }

  function where(job) {
    return job.board ? { key: "where_board", args: { n: job.board } } : "";
  }

  function queued(job) {
    const again = job.attempts >= 1 ? { key: "st_requeued" } : null;
    let line;
    if (job.show_paused && job.queue_position) line = ["st_paused_n", { n: job.queue_position }];
    else if (job.show_paused) line = ["st_paused", {}];
    else if (!job.queue_position) line = ["st_in_queue", {}];
    else if (job.queue_position <= 1) line = ["st_next", { eta: duration(job.eta_s) }];
    else line = ["st_number", { n: job.queue_position, eta: duration(job.eta_s) }];
    if (!again) return line;
    return ["two", { a: again, b: { key: line[0], args: line[1] } }];
  }

  // [key, args] of the sentence about ``job``; errorWords words a late refusal's code.
  function words(job, errorWords) {
    const who = { drone: drone(job), where: where(job), pct: pct(job.progress) };
    // the operator's reason: plain text the kiosk cut to a line, shown as text (never markup)
    const said = { reason: job.reason };
    switch (job.state) {
      case "submitted": case "awaiting_approval": return ["st_approval", {}];
      case "queued": return queued(job);
      case "assigned":
        return [job.attempts >= 2 ? "st_restarted" : "st_assigned", who];
      case "writing":
        return [job.attempts >= 2 ? "st_restarted_pct" : "st_writing", who];
      case "done": return ["st_done", who];
      case "failed":
        return job.failure === "writing_bounds" ? ["st_failed_bounds", who] : ["st_failed", {}];
      case "cancelled": return job.reason ? ["st_cancelled_reason", said] : ["st_cancelled", {}];
      case "rejected": return job.reason ? ["st_rejected_reason", said] : ["st_rejected", {}];
      case "sending": return ["st_sending", {}];
      case "checking": return ["st_checking", {}];
      case "refused": return errorWords({ code: job.refusal || "refused" });
      default: return ["st_wait", {}];
    }
  }

  // Sentences under the pictures of a written character (done, or failed on its bounds): time,
  // where to look, how close, how much overlaps.
  function resultWords(job) {
    const out = [];
    const m = job.metrics;
    if (m) out.push(["done_time", { secs: Math.round(m.duration_s) }]);
    if (job.board) out.push(["look_at", { n: job.board }]);
    if (m) {
      // null: the pen never came down, nothing was measured (never shown as 0 cm)
      if (m.rmse_pen_down_m == null) {
        out.push(["acc_none", {}]);
      } else {
        const cm = m.rmse_pen_down_m * 100;
        const key = cm < 1 ? "acc_very_close" : cm < 3 ? "acc_close" : "acc_off";
        out.push([key, { cm: cm.toFixed(1) }]);
      }
      if (m.flown_fraction != null && m.flown_fraction < 1) {
        out.push(["partial", { pct: Math.round(m.flown_fraction * 100) }]);
      }
      if (m.iou != null) out.push(["overlap", { pct: Math.round(m.iou * 100) }]);
      if (m.written) out.push(["written_note", {}]);
    }
    return out;
  }

  return { words, resultWords, duration };
})();
