// Line width of a drawing, per point, in metres (docs/formats.md: the point's "w"), for boards
// whose pen writes with a width. From the pointer's pressure where the device reports it (a
// pen or a pressure screen: values other than the 0.5 every pressed mouse and plain touch
// report), otherwise from the drawing speed, as a brush: a quick line is thin, a slow one wide.
"use strict";

window.SkyquillWidths = (() => {
  const FAST_PX_S = 1200;  // this speed or faster draws the narrowest line (CSS px per second)
  const SPAN = 2;          // speed from the points this many before and after

  // Whether the stroke's points ([x, y, t, pressure]) carry a real pressure.
  function hasPressure(stroke) {
    return stroke.some((p) => p[3] > 0 && Math.abs(p[3] - 0.5) > 1e-3);
  }

  // Speed in px/s at each point, over a few neighbours (0 where no time passed).
  function speeds(stroke) {
    return stroke.map((_, i) => {
      const a = Math.max(0, i - SPAN);
      const b = Math.min(stroke.length - 1, i + SPAN);
      let length = 0;
      for (let k = a + 1; k <= b; k += 1) {
        length += Math.hypot(stroke[k][0] - stroke[k - 1][0], stroke[k][1] - stroke[k - 1][1]);
      }
      const dt = stroke[b][2] - stroke[a][2];
      return dt > 0 ? length / dt : 0;
    });
  }

  // Width in metres of each point of ``stroke``, within ``range`` [narrowest, widest].
  function strokeWidths(stroke, range) {
    const [low, high] = range;
    const clamp = (v) => Math.min(1, Math.max(0, v));
    const fractions = hasPressure(stroke)
      ? stroke.map((p) => clamp(p[3]))
      : speeds(stroke).map((v) => 1 - clamp(v / FAST_PX_S));
    return fractions.map((f) => Math.round((low + f * (high - low)) * 1e5) / 1e5);
  }

  // The strokes as points {x, y, t, w} (the pressure is in w), or as they are without a range.
  function withWidths(strokes, range) {
    if (!range) return strokes;
    return strokes.map((stroke) => {
      const widths = strokeWidths(stroke, range);
      return stroke.map((p, i) => ({ x: p[0], y: p[1], t: p[2], w: widths[i] }));
    });
  }

  return { hasPressure, strokeWidths, withWidths };
})();
