#!/usr/bin/env python3
"""Writes design.toml: a men's size-42 upper as one surface cut by style lines into a toe cap, a
vamp and a lateral and a medial quarter, each cut in pairs (left and right shoe).

Run from this folder: python3 make.py. Last axes: x from the heel (0) to the toe (270 mm), y across
(lateral side +y: the surface as drawn is a left shoe's upper), z up from the featherline plane (the
flat last bottom, z = 0). Bezier points are listed with the second index (v) fastest.

The surface is five bicubic Bezier patches welded along their sides: the vamp patch (across the
foot from the medial to the lateral featherline, from the throat to the toe) split at u = 0.3 and
u = 0.7 into its medial, centre and lateral thirds, and the lateral and medial quarters, whose
front edges are the exact sub-curves of the throat below u = 0.3 and above u = 0.7 and which meet
at the heel's centre line. Its boundary is the featherline all round and the top line (throat
opening and collar).

Style lines: the toe cap along the old toe-cap stitch line (v = 0.62 of the vamp patch), the vamp
line on each side from the top line down and forward to the featherline, and the back seam at the
heel's centre line; three notches on each vamp line and on the toe cap, two on the back seam.

Allowances by edge, as an upper is made: the toe cap lies on the vamp and the vamp on the
quarters (lapped seams: the piece on top cut raw, the one under it with a 10 mm underlay), the
back seam is closed face to face on a 2 mm margin, the featherline carries a 16 mm lasting margin
(pulled over the last and cemented under the insole) and the top line a 5 mm allowance folded in.

Grading: base size 42 (Paris points); 40 and 44 scaled about the heel's foot (the origin) by two
Paris points (13.33 mm) on the 274 mm last length and two girth steps (5 mm each on a 245 mm ball
girth) across and up, so length and girth grade differently, as lasts do.
"""

import pathlib

HERE = pathlib.Path(__file__).resolve().parent
U_TOP = 0.7  # where the lateral quarter's top line meets the vamp throat
TOE_V = 0.62  # the toe-cap line across the vamp patch

# Vamp: rows i across the foot (0 medial featherline .. 3 lateral featherline), columns j from
# the throat (0) to the toe featherline (3).
VAMP = [
    [[152, -47, 0], [195, -52, 0], [242, -46, 0], [255, -34, 0]],
    [[148, -52, 100], [192, -56, 78], [245, -48, 48], [275, -30, 0]],
    [[148, 52, 100], [192, 56, 78], [245, 48, 48], [275, 30, 0]],
    [[152, 47, 0], [195, 52, 0], [242, 46, 0], [255, 34, 0]],
]


def lerp(a, b, t):
    return [x + (y - x) * t for x, y in zip(a, b)]


def bez(ctrl, t):
    pts = [list(p) for p in ctrl]
    while len(pts) > 1:
        pts = [lerp(pts[k], pts[k + 1], t) for k in range(len(pts) - 1)]
    return pts[0]


def split(ctrl, t):
    """Control points of the cubic on [0, t] and on [t, 1]."""
    a, b, c, d = ctrl
    ab, bc, cd = lerp(a, b, t), lerp(b, c, t), lerp(c, d, t)
    abc, bcd = lerp(ab, bc, t), lerp(bc, cd, t)
    p = lerp(abc, bcd, t)
    return [a, ab, abc, p], [p, bcd, cd, d]


def sub(ctrl, t0, t1):
    """Control points of the cubic restricted to [t0, t1]."""
    _, right = split(ctrl, t0)
    left, _ = split(right, (t1 - t0) / (1 - t0))
    return left


def vamp_part(u0, u1):
    """The vamp patch for u in [u0, u1], rows from the lateral to the medial side (reversed, so
    that the normal points out of the shoe as on the quarters), columns throat to toe."""
    cols = [sub([VAMP[i][j] for i in range(4)], u0, u1) for j in range(4)]
    return [[cols[j][i] for j in range(4)] for i in reversed(range(4))]


def vamp_at(u, v):
    return bez([bez(VAMP[i], v) for i in range(4)], u)


def patch_at(ctrl, u, v):
    return bez([bez(row, v) for row in ctrl], u)


def mirror(p):
    return [p[0], -p[1], p[2]]


def fmt(x):
    s = f"{x:.6f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def p3(p):
    return "[" + ", ".join(fmt(c) for c in p) + "]"


def lateral_quarter():
    """Rows i from the vamp seam (0) back to the heel centre line (3), columns j from the
    featherline (0) to the top line (3). The heel wall bulges back at counter height and the
    ankle pulls the upper edge inwards: a doubly curved piece."""
    throat = [VAMP[i][0] for i in range(4)]
    front = sub(throat, U_TOP, 1.0)
    front.reverse()  # featherline (j = 0) up to the top line (j = 3)
    quarter = [front]
    cols = [
        # x, y at the featherline; y at the top line; top-line height; bulge (outwards, mm)
        (92, 50, 40, 52, 6),
        (18, 36, 28, 62, 5),
        (-4, 0, 0, 72, 0),
    ]
    for x, y0, y3, ztop, bulge in cols:
        col = []
        for j in range(4):
            t = j / 3
            y = y0 + (y3 - y0) * t + (bulge if j in (1, 2) else 0) * (1 if y0 else 0)
            xj = x - (6 if (y0 == 0 and j == 1) else 0) + (3 if (y0 == 0 and j == 3) else 0)
            col.append([xj, y, ztop * t])
        quarter.append(col)
    return quarter


def main():
    lateral = lateral_quarter()
    # The medial quarter: the lateral one mirrored (y → −y), its rows reversed (heel to front)
    # so that its normal points out of the shoe too.
    medial = [[mirror(p) for p in row] for row in reversed(lateral)]
    patches = [
        ("vamp, medial third", vamp_part(0.0, 0.3)),
        ("vamp, centre third", vamp_part(0.3, 0.7)),
        ("vamp, lateral third", vamp_part(0.7, 1.0)),
        ("lateral quarter", lateral),
        ("medial quarter", medial),
    ]
    heel = [lateral[3][j] for j in range(4)]

    lines = [
        "# Generated by make.py; do not edit by hand.",
        'units = "mm"',
        "",
        "[[part]]",
        'name = "upper"',
        "[part.surface]",
        'type = "patches"',
    ]
    for what, ctrl in patches:
        lines.append(f"[[part.surface.patches]]  # {what}")
        lines.append('type = "bezier"')
        lines.append("degree = [3, 3]")
        lines.append("points = [")
        for row in ctrl:
            lines.append("  " + ", ".join(p3(p) for p in row) + ",")
        lines.append("]")
    lines.append("")

    def line(name, pts, notches, comment, finish):
        lines.append("[[part.line]]")
        lines.append(f"# {comment}")
        lines.append(f'name = "{name}"')
        lines.append("points = [" + ", ".join(p3(p) for p in pts) + "]")
        lines.append("notches = [" + ", ".join(p3(p) for p in notches) + "]")
        lines.append(finish)
        lines.append("")

    toe = [vamp_at(u, TOE_V) for u in (0.0, 0.1, 0.25, 0.4, 0.5, 0.6, 0.75, 0.9, 1.0)]
    line(
        "toe-cap",
        toe,
        [vamp_at(u, TOE_V) for u in (0.25, 0.5, 0.75)],
        "The toe cap along the old toe-cap stitch line, featherline to featherline; lapped: the\n"
        "# toe cap on top, cut raw, the vamp under it with the underlay.",
        'lap = "toe cap"',
    )
    # The vamp line: from the top line at the throat (u = 0.7) down and forward to the
    # featherline 14 mm ahead of the quarter's old front edge.
    vamp_uv = [(U_TOP, 0.0), (0.76, 0.035), (0.84, 0.07), (0.92, 0.1), (0.98, 0.12), (1.0, 0.125)]
    notch_uv = [(0.8, 0.052), (0.88, 0.086), (0.95, 0.111)]
    line(
        "vamp-lateral",
        [vamp_at(u, v) for u, v in vamp_uv],
        [vamp_at(u, v) for u, v in notch_uv],
        "The lateral vamp line, top line to featherline; lapped: the vamp on the quarter.",
        'lap = "vamp"',
    )
    line(
        "vamp-medial",
        [vamp_at(1 - u, v) for u, v in vamp_uv],
        [vamp_at(1 - u, v) for u, v in notch_uv],
        "The medial vamp line (the lateral one mirrored); lapped: the vamp on the quarter.",
        'lap = "vamp"',
    )
    line(
        "back",
        [bez(heel, t) for t in (0.0, 0.2, 0.4, 0.6, 0.8, 1.0)],
        [bez(heel, t) for t in (0.35, 0.7)],
        "The back seam at the heel's centre line, featherline to collar: closed face to face.",
        "allowance_mm = 2",
    )

    def edge(name, at, allowance, kind, comment):
        lines.append("[[part.edge]]")
        lines.append(f"# {comment}")
        lines.append(f'name = "{name}"')
        lines.append(f"from = {p3(at)}")
        lines.append(f"to = {p3(at)}")
        lines.append(f"allowance_mm = {allowance}")
        lines.append(f'kind = "{kind}"')
        lines.append("")

    edge(
        "featherline",
        heel[0],
        16,
        "lasting",
        "The whole featherline (from = to: the outline loop through the heel's foot): the\n"
        "# lasting margin pulled over the last.",
    )
    edge(
        "topline",
        heel[3],
        5,
        "fold",
        "The whole top line, throat and collar: folded in.",
    )

    def piece(name, at, grain, comment):
        lines.append("[[part.piece]]")
        lines.append(f"# {comment}")
        lines.append(f'name = "{name}"')
        lines.append(f"at = {p3(at)}")
        lines.append("pairs = 1")
        lines.append('material = "leather"')
        lines.append("seam_allowance_mm = 8")
        lines.append(f"grain = [{p3(grain[0])}, {p3(grain[1])}]")
        lines.append("")

    piece(
        "toe cap",
        vamp_at(0.5, 0.85),
        [vamp_at(0.5, TOE_V), vamp_at(0.5, 1.0)],
        "Grain along the foot, towards the toe.",
    )
    piece(
        "vamp",
        vamp_at(0.5, 0.3),
        [vamp_at(0.5, 0.0), vamp_at(0.5, TOE_V)],
        "Grain along the foot, from the throat towards the toe.",
    )
    piece(
        "lateral quarter",
        patch_at(lateral, 0.4, 0.4),
        [[100, 52, 20], [30, 40, 20]],
        "Grain fore-and-aft.",
    )
    piece(
        "medial quarter",
        patch_at(medial, 0.6, 0.4),
        [[100, -52, 20], [30, -40, 20]],
        "Grain fore-and-aft.",
    )
    # Paris points: 6.667 mm of last length a size; girth 5 mm a size on a 245 mm ball girth.
    length, girth = 274.0, 245.0
    lines.append("[grading]")
    lines.append("# Sizes 40 and 44 scaled about the heel's foot: length and girth grade differently.")
    lines.append('base = "42"')
    lines.append("origin = [0, 0, 0]")
    for size in (40, 42, 44):
        steps = size - 42
        lines.append("[[grading.size]]")
        lines.append(f'name = "{size}"')
        if steps:
            sx = 1 + steps * (20 / 3) / length
            sg = 1 + steps * 5.0 / girth
            lines.append(f"scale = [{sx:.5f}, {sg:.5f}, {sg:.5f}]")
    lines.append("")
    (HERE / "design.toml").write_text("\n".join(lines))


if __name__ == "__main__":
    main()
