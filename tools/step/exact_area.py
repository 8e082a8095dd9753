#!/usr/bin/env python3
"""The exact area of a STEP face, independent of flatcut and of OpenCASCADE, where a closed form
reaches it: a plane face bounded by lines, circles and ellipses (the shoelace formula over the
curves sampled at 60,000 points per arc: the chords' sliver is about 2e-9 of the area), a sphere
face likewise (the solid angle its boundary encloses, as a fan of spherical triangles). Other
faces: None.

    python3 tools/step/exact_area.py FILE.step ID...

Prints, per face `#id`, its surface, the exact area and how far its edges lie off the surface.
"""

import re
import sys

import numpy as np

def load(path):
    txt=open(path).read()
    data=txt[txt.index('DATA;'):]
    ents={}
    for m in re.finditer(r'#(\d+)\s*=\s*(.*?);\s*(?=#\d+\s*=|ENDSEC)', data, re.S):
        ents[int(m.group(1))]=' '.join(m.group(2).split())
    return ents

class Unsupported(Exception):
    """A surface or curve no closed form here covers."""


def args_of(s):
    # split top-level args of NAME(...)
    m = re.match(r"([A-Z0-9_]*)\s*\((.*)\)$", s, re.S)
    name, body = m.group(1), m.group(2)
    out, depth, cur = [], 0, ''
    for ch in body:
        if ch == '(':
            depth += 1
        elif ch == ')':
            depth -= 1
        if ch == ',' and depth == 0:
            out.append(cur.strip()); cur = ''
        else:
            cur += ch
    out.append(cur.strip())
    return name, out

E = {}


def ent(r):
    return args_of(E[int(r.strip().lstrip('#'))])
def nums(s): return np.array([float(x) for x in s.strip('()').split(',')])
def point(r): n, a = ent(r); assert n == 'CARTESIAN_POINT'; return nums(a[1])
def direction(r): n, a = ent(r); v = nums(a[1]); return v / np.linalg.norm(v)
def axis2(r):
    n, a = ent(r)
    o = point(a[1]); z = direction(a[2]) if a[2] != '$' else np.array([0, 0, 1.])
    x = direction(a[3]) if a[3] != '$' else np.array([1., 0, 0])
    x = x - z * (x @ z); x /= np.linalg.norm(x)
    return o, x, np.cross(z, x), z
def vertex(r): n, a = ent(r); return point(a[1])

N = 60001
def sample_edge(ec, fwd):
    n, a = ent(ec)
    p0, p1, crv, same = vertex(a[1]), vertex(a[2]), a[3], a[4] == '.T.'
    cn, ca = ent(crv)
    if cn == 'LINE':
        pts = np.array([p0, p1])
    elif cn in ('CIRCLE', 'ELLIPSE'):
        o, x, y, z = axis2(ca[1])
        r1 = float(ca[2]); r2 = float(ca[3]) if cn == 'ELLIPSE' else r1
        def t_of(p):
            d = p - o
            return np.arctan2((d @ y) / r2, (d @ x) / r1)
        def off(p):
            d = p - o; t = t_of(p)
            return np.linalg.norm(o + r1 * np.cos(t) * x + r2 * np.sin(t) * y - p)
        assert off(p0) < 1e-6 and off(p1) < 1e-6, (ec, off(p0), off(p1))
        t0, t1 = t_of(p0), t_of(p1)
        if same:
            if t1 <= t0 + 1e-12: t1 += 2 * np.pi
        else:
            if t1 >= t0 - 1e-12: t1 -= 2 * np.pi
        t = np.linspace(t0, t1, N)
        pts = o + np.outer(r1 * np.cos(t), x) + np.outer(r2 * np.sin(t), y)
        pts[0], pts[-1] = p0, p1
    else:
        raise Unsupported(cn)
    return pts if fwd else pts[::-1]

def face(fid):
    n, a = ent(f'#{fid}')
    assert n == 'ADVANCED_FACE'
    sn, sa = ent(a[2])
    loops = []
    for b in re.findall(r'#\d+', a[1]):
        bn, ba = ent(b)
        ln, la = ent(ba[1])
        pts = []
        for oe in re.findall(r'#\d+', la[1]):
            on, oa = ent(oe)
            seg = sample_edge(oa[3], oa[4] == '.T.')
            pts.append(seg[:-1])
        lp = np.vstack(pts)
        if ba[2] != '.T.':
            lp = lp[::-1]
        loops.append(lp)
    return sn, sa, loops, a[3] == '.T.'

def area(fid):
    sn, sa, loops, same = face(fid)
    if sn == 'PLANE':
        o, x, y, z = axis2(sa[1])
        off = max(abs((lp - o) @ z).max() for lp in loops)
        tot = 0
        for lp in loops:
            u, v = (lp - o) @ x, (lp - o) @ y
            tot += 0.5 * np.sum(u * np.roll(v, -1) - np.roll(u, -1) * v)
        return sn, abs(tot), off, [0.5 * np.sum(((lp - o) @ x) * np.roll((lp - o) @ y, -1) - np.roll((lp - o) @ x, -1) * ((lp - o) @ y)) for lp in loops]
    if sn == 'SPHERICAL_SURFACE':
        o, x, y, z = axis2(sa[1]); R = float(sa[2])
        off = max(abs(np.linalg.norm(lp - o, axis=1) - R).max() for lp in loops)
        tot = 0
        for lp in loops:
            d = (lp - o) / np.linalg.norm(lp - o, axis=1)[:, None]
            c = d.mean(0); c /= np.linalg.norm(c)
            b, e = d, np.roll(d, -1, axis=0)
            num = np.einsum('ij,ij->i', np.cross(b, e), c[None, :].repeat(len(b), 0))
            den = 1 + b @ c + e @ c + np.einsum('ij,ij->i', b, e)
            tot += np.sum(2 * np.arctan2(num, den))
        return sn, abs(tot) * R * R, off, None
    raise Unsupported(sn)



def exact_area(entities, fid):
    """(surface, exact area in the file's units, the edges' largest distance off the surface),
    or None where no closed form applies."""
    E.clear()
    E.update(entities)
    try:
        sn, a, off, _ = area(fid)
    except (Unsupported, KeyError, AttributeError, ValueError, AssertionError, IndexError, TypeError):
        return None
    return sn, a, off


def main():
    entities = load(sys.argv[1])
    for fid in sys.argv[2:]:
        got = exact_area(entities, int(fid.lstrip('#')))
        if got is None:
            print(f"#{fid.lstrip('#')}: no closed form")
        else:
            print(f"#{fid.lstrip('#')} {got[0]}: exact {got[1]:.6f}, edges off the surface by {got[2]:.2e}")


if __name__ == "__main__":
    main()
