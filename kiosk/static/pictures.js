// Pictures on canvases, drawn as data: the planned path (ink over air moves) and the ink the
// drone left (a 1-bit raster, see docs/protocol.md "WrittenInk"), both in the writing area's
// frame (metres, origin at the centre, y up) at the same scale, so they sit side by side.
"use strict";

window.SkyquillPictures = (() => {
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

  // Metres in the writing area -> canvas pixels: the area fills 92% of the canvas.
  function mapper(w, h, areaM) {
    const [aw, ah] = areaM;
    const scale = Math.min(w / aw, h / ah) * 0.92;
    return { scale, map: (p) => [w / 2 + p[0] * scale, h / 2 - p[1] * scale] };
  }

  // Runs of equal pen state: [start, end, down]; the air moves show as dashes.
  function penRuns(path) {
    const runs = [];
    let start = 0;
    while (start < path.length - 1) {
      const down = Boolean(path[start + 1][2] && path[start][2]);
      let end = start + 1;
      while (end < path.length - 1 && Boolean(path[end + 1][2] && path[end][2]) === down) end += 1;
      runs.push([start, end, down]);
      start = end;
    }
    return runs;
  }

  function polyline(ctx, path, map, start, end) {
    ctx.beginPath();
    const first = map(path[start]);
    ctx.moveTo(first[0], first[1]);
    for (let i = start + 1; i <= end; i += 1) {
      const p = map(path[i]);
      ctx.lineTo(p[0], p[1]);
    }
    ctx.stroke();
  }

  // Ink of one pen-down run: in one line of the brush's plain width, or, where the plan gives
  // a width per point (path[i][3], metres), segment by segment at that width to scale.
  function drawInkRun(ctx, path, map, scale, start, end) {
    if (path[start].length < 4) {
      ctx.lineWidth = 6;
      polyline(ctx, path, map, start, end);
      return;
    }
    for (let i = start + 1; i <= end; i += 1) {
      const a = map(path[i - 1]);
      const b = map(path[i]);
      ctx.lineWidth = Math.max(1, ((path[i - 1][3] + path[i][3]) / 2) * scale);
      ctx.beginPath();
      ctx.moveTo(a[0], a[1]);
      ctx.lineTo(b[0], b[1]);
      ctx.stroke();
    }
  }

  // The path up to sample ``upto``: air moves first, ink over them (never air over ink).
  function drawPath(canvas, preview, upto = Infinity) {
    const { ctx, w, h } = fitCanvas(canvas);
    ctx.clearRect(0, 0, w, h);
    drawGuides(ctx, w, h);
    const { scale, map } = mapper(w, h, preview.writing_area_m);
    ctx.lineCap = "round";
    ctx.lineJoin = "round";
    const path = preview.path;   // [x, y, pen_down] or [x, y, pen_down, width_m]
    const runs = penRuns(path);
    for (const layer of [false, true]) {
      for (const [start, end, down] of runs) {
        if (down !== layer || start >= upto) continue;
        ctx.strokeStyle = down ? "#14213d" : "#6f7a91";
        if (down) {
          ctx.setLineDash([]);
          drawInkRun(ctx, path, map, scale, start, Math.min(end, upto));
          continue;
        }
        ctx.lineWidth = 1.5;
        ctx.setLineDash([5, 5]);
        polyline(ctx, path, map, start, Math.min(end, upto));
      }
    }
    ctx.setLineDash([]);
    if (upto < path.length) {  // where the brush is now
      const [x, y] = map(path[Math.max(0, Math.floor(upto))]);
      ctx.fillStyle = "#b44703";
      ctx.beginPath();
      ctx.arc(x, y, 6, 0, 2 * Math.PI);
      ctx.fill();
      return;
    }
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

  // The writing order, played in about 3 s (at once for visitors who ask for less motion).
  function animatePath(canvas, preview) {
    const n = preview.path.length;
    const still = window.matchMedia("(prefers-reduced-motion: reduce)").matches;
    canvas.dataset.drawn = "0";
    const t0 = performance.now();
    const frame = (now) => {
      if (canvas.dataset.playing !== String(t0)) return;  // a newer preview took over
      const upto = still ? n : Math.floor((n * (now - t0)) / 3000);
      drawPath(canvas, preview, upto >= n ? Infinity : upto);
      if (upto >= n) { canvas.dataset.drawn = "1"; return; }
      requestAnimationFrame(frame);
    };
    canvas.dataset.playing = String(t0);
    requestAnimationFrame(frame);
  }

  // The ink raster as RGBA pixels (ink dark, the rest transparent); null when malformed.
  function inkImage(written) {
    const { width_px: w, height_px: h } = written;
    let bytes;
    try { bytes = atob(written.bits); } catch (err) { return null; }
    if (written.format !== "bitmap1" || bytes.length !== Math.ceil((w * h) / 8)) return null;
    const image = new ImageData(w, h);
    let inked = 0;
    for (let i = 0; i < w * h; i += 1) {
      if ((bytes.charCodeAt(i >> 3) >> (7 - (i & 7))) & 1) {
        image.data.set([20, 33, 61, 255], 4 * i);
        inked += 1;
      }
    }
    return { image, inked };
  }

  // The ink the drone left, placed by its extent in the same frame as the plan.
  function drawInk(canvas, written, areaM) {
    const { ctx, w, h } = fitCanvas(canvas);
    ctx.clearRect(0, 0, w, h);
    drawGuides(ctx, w, h);
    const decoded = inkImage(written);
    if (!decoded) return 0;
    const tile = document.createElement("canvas");
    tile.width = written.width_px;
    tile.height = written.height_px;
    tile.getContext("2d").putImageData(decoded.image, 0, 0);
    const [x0, y0, x1, y1] = written.extent_m_board;
    const { scale, map } = mapper(w, h, areaM || [x1 - x0, y1 - y0]);
    const [left, top] = map([x0, y1]);
    ctx.imageSmoothingEnabled = true;
    ctx.drawImage(tile, left, top, (x1 - x0) * scale, (y1 - y0) * scale);
    canvas.dataset.inked = String(decoded.inked);
    return decoded.inked;
  }

  return { fitCanvas, drawGuides, drawPath, animatePath, drawInk };
})();
