#!/usr/bin/env python3
"""Independent check of a flatcut G-code job with a third-party parser (gcodeparser).

Usage: tools/gcode/check_gcodeparser.py job.gcode [work_w work_h]
Checks: every command is one GRBL 1.1 accepts, every line at most 70 characters, no '%', the
job ends with M2 and the tool off; all XY motion inside the work area; prints the tool-on length.
"""
import math
import sys

from gcodeparser import GcodeParser

ALLOWED = {("G", n) for n in (0, 1, 2, 3, 4, 17, 21, 90, 94)} | {("M", n) for n in (2, 3, 4, 5, 8, 9)}


def main():
    path = sys.argv[1]
    w = float(sys.argv[2]) if len(sys.argv) > 2 else math.inf
    h = float(sys.argv[3]) if len(sys.argv) > 3 else math.inf  # noqa: E501
    text = open(path, encoding="ascii").read()
    for n, line in enumerate(text.split("\n"), 1):
        assert len(line) <= 70, f"line {n} longer than 70 characters"
        assert "%" not in line, f"line {n}: '%' is rejected by GRBL"
    x = y = 0.0
    on = False
    length = 0.0
    last = None
    for ln in GcodeParser(text).lines:
        cmd = ln.command
        assert cmd in ALLOWED, f"unsupported command {cmd} in: {ln.gcode_str}"
        last = cmd
        p = ln.params
        if cmd[0] == "M" and cmd[1] in (3, 4):
            on = p.get("S", 0) > 0
        if cmd[0] == "M" and cmd[1] in (2, 5):
            on = False
        if cmd[0] == "G" and cmd[1] in (0, 1, 2, 3):
            nx, ny = p.get("X", x), p.get("Y", y)
            assert -1e-6 <= nx <= w + 1e-6 and -1e-6 <= ny <= h + 1e-6, f"outside the work area: {ln.gcode_str}"
            if on and cmd[1] != 0:
                length += math.hypot(nx - x, ny - y)  # chords for arcs: a lower bound
            x, y = nx, ny
    assert last == ("M", 2), "the job must end with M2"
    assert not on, "the tool must be off at the end"
    print(f"{path}: OK, tool-on length ≥ {length:.1f} mm (arcs as chords)")


if __name__ == "__main__":
    main()
