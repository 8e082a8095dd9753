// Colours: the strain heat map uses the report's own diverging map (its stops come from the
// server with every flattening, flatcut_report::DIVERGING_STOPS), so the page and report.html
// agree; pieces get distinct soft colours.

/** [r, g, b] in 0..1 of `stops` (0..255 triples) at t in [-1, 1]. */
export function diverging(stops, t) {
  if (!Number.isFinite(t)) t = 1;
  const u = Math.min(1, Math.max(0, 0.5 * (t + 1))) * (stops.length - 1);
  const i = Math.min(stops.length - 2, Math.floor(u));
  const f = u - i;
  return [0, 1, 2].map((k) => (stops[i][k] * (1 - f) + stops[i + 1][k] * f) / 255);
}

const PALETTE = [
  [0.55, 0.71, 0.87], [0.96, 0.73, 0.45], [0.62, 0.82, 0.58], [0.86, 0.6, 0.62],
  [0.76, 0.68, 0.88], [0.84, 0.76, 0.56], [0.56, 0.82, 0.8], [0.93, 0.68, 0.82],
];

/** A soft colour for piece or region number k. */
export function pieceColour(k) {
  return PALETTE[((k % PALETTE.length) + PALETTE.length) % PALETTE.length];
}

/**
 * The heat map's scale: against the material's limits when there are some (red at the stretch
 * limit, blue at the compression limit), else ± the largest strain of any piece.
 */
export function heatScale(pieces) {
  const p0 = pieces[0] || {};
  if (p0.limit_stretch_pct != null || p0.limit_compress_pct != null) {
    return { stretch: p0.limit_stretch_pct ?? null, compress: p0.limit_compress_pct ?? null, limits: true };
  }
  let m = 0.01;
  for (const p of pieces) m = Math.max(m, p.stretch_max_pct, p.compress_max_pct);
  return { stretch: m, compress: m, limits: false };
}

/** t in [-1, 1] of a face's signed strain (%) on `scale`; beyond ±1 is beyond the limit. */
export function heatT(scale, v) {
  if (v >= 0) return scale.stretch ? v / scale.stretch : (v > 0 ? 2 : 0);
  return scale.compress ? v / scale.compress : -2;
}

/** The colour of a face: beyond a limit it is darkened, so an excess is seen at once. */
export function heatColour(stops, scale, v) {
  const t = heatT(scale, v);
  const c = diverging(stops, t);
  return Math.abs(t) > 1 ? c.map((x) => x * 0.55) : c;
}
