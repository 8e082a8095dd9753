#!/usr/bin/env python3
"""Replays the shop-floor cases against a real GRBL 1.1h controller (a board on a serial port,
or grbl-sim behind tools/grbl-real/link.py), with `flatcut send --port`:

  A   a late banner: the board resets when the port opens and its banner comes after the
      sender's boot wait; a resume must be refused ("restarted"), nothing moved.
  B   a restart while the port was closed (power cycle, no reset on open): a resume must be
      refused naming the position against the journal, and complete with --origin-confirmed.
  C   a program pause (square, M0, square): without an operator the pause aborts after the first
      square, with every line up to the M0 executed; the resume continues after the pause and
      sends none of the first square again.
  G92 the operator's G92 origin is kept across the sender's connection (boards that do not
      reset on open: a reset clears G92).
  HUP SIGHUP during a send ends it with the tool off, confirmed by $G.
  LASER a laser job ($32=1) stopped by a line the controller refuses: tool off, confirmed by $G.

Without GRBL_REAL_LINK it prints why and exits 0 (skipped). Environment:

  GRBL_REAL_LINK           the controller's port (required)
  GRBL_REAL_BAUD           its baud rate (115200)
  GRBL_REAL_RESETS_ON_OPEN 1 (an Arduino's DTR reset, the default) or 0
  GRBL_REAL_BOOT_WAIT_MS   the --boot-wait case A uses, shorter than the board's boot (300)
  GRBL_REAL_POWER_CYCLE    a shell command that power-cycles the controller (case B; skipped
                           without it): a switched USB hub, or `kill -USR1 <link.py's pid>`
  GRBL_REAL_LASER          1: case LASER may set $32=1 (set back to its value afterwards)
  FLATCUT                  the flatcut binary (default: flatcut on PATH)
  GRBL_REAL_CASES          which cases, comma-separated (default: all the link allows)

The machine moves: a few millimetres from where it stands, pen or tool up (Z 0). Exit status 0
when every case run passed; each case prints PASS, FAIL (with what differed) or SKIP (why).
"""

import os
import select
import shutil
import signal
import subprocess
import sys
import tempfile
import termios
import time
import tty

BAUDS = {9600: termios.B9600, 57600: termios.B57600, 115200: termios.B115200,
         230400: termios.B230400}


class Port:
    """The controller's port, raw, for setting up and querying between the cases."""

    def __init__(self, path, baud, resets_on_open):
        self.fd = os.open(path, os.O_RDWR | os.O_NOCTTY)
        tty.setraw(self.fd)
        attrs = termios.tcgetattr(self.fd)
        speed = BAUDS.get(baud, termios.B115200)
        attrs[4] = attrs[5] = speed
        termios.tcsetattr(self.fd, termios.TCSANOW, attrs)
        if resets_on_open:
            self.read_until(b"for help]", 10.0)

    def read_until(self, token, timeout):
        out, end = b"", time.monotonic() + timeout
        while token not in out and time.monotonic() < end:
            r, _, _ = select.select([self.fd], [], [], 0.05)
            if r:
                try:
                    out += os.read(self.fd, 4096)
                except OSError:
                    break
        return out.decode(errors="replace")

    def command(self, line, timeout=10.0):
        os.write(self.fd, line.encode() + b"\n")
        return self.read_until(b"ok\r\n", timeout)

    def status(self):
        os.write(self.fd, b"?")
        return self.read_until(b">\r\n", 2.0)

    def wait_idle(self, timeout=60.0):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if "<Idle" in self.status():
                return True
            time.sleep(0.2)
        return False

    def close(self):
        os.close(self.fd)


class Replay:
    def __init__(self):
        self.link = os.environ["GRBL_REAL_LINK"]
        self.baud = int(os.environ.get("GRBL_REAL_BAUD", "115200"))
        self.resets = os.environ.get("GRBL_REAL_RESETS_ON_OPEN", "1") != "0"
        self.boot_wait = os.environ.get("GRBL_REAL_BOOT_WAIT_MS", "300")
        self.power_cycle = os.environ.get("GRBL_REAL_POWER_CYCLE")
        self.laser_ok = os.environ.get("GRBL_REAL_LASER") == "1"
        self.flatcut = os.environ.get("FLATCUT") or shutil.which("flatcut") or "flatcut"
        self.dir = tempfile.mkdtemp(prefix="grbl-real-")
        self.results = []

    # ----- helpers -----

    def port(self):
        return Port(self.link, self.baud, self.resets)

    def job(self, name, text):
        path = os.path.join(self.dir, name)
        with open(path, "w") as f:
            f.write(text)
        return path

    def send(self, job, *flags, timeout=300):
        """Runs `flatcut send` (stdin not a terminal); returns (exit code, output)."""
        cmd = [self.flatcut, "send", job, "--port", self.link, "--baud", str(self.baud), *flags]
        p = subprocess.run(cmd, stdin=subprocess.DEVNULL, capture_output=True, text=True,
                           timeout=timeout)
        return p.returncode, p.stdout + p.stderr

    def send_then_signal(self, job, sig, after_acks, *flags):
        """Starts `flatcut send`, sends it `sig` once the journal holds `after_acks` answered
        lines; returns (exit code, output, journal path)."""
        journal = job + ".journal"
        cmd = [self.flatcut, "send", job, "--port", self.link, "--baud", str(self.baud),
               "--journal", journal, *flags]
        p = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                             stderr=subprocess.STDOUT, text=True)
        end = time.monotonic() + 120
        while time.monotonic() < end and p.poll() is None:
            if acks(journal) >= after_acks:
                break
            time.sleep(0.05)
        if p.poll() is None:
            p.send_signal(sig)
        out, _ = p.communicate(timeout=120)
        return p.returncode, out, journal

    def record(self, case, ok, detail):
        self.results.append((case, "PASS" if ok else "FAIL", detail))
        print(f"{case:6} {'PASS' if ok else 'FAIL'}  {detail}", flush=True)

    def skip(self, case, why):
        self.results.append((case, "SKIP", why))
        print(f"{case:6} SKIP  {why}", flush=True)

    # ----- the cases -----

    def case_a(self):
        if not self.resets:
            return self.skip("A", "the board does not reset when the port opens")
        job = self.job("a.gcode", strokes(12))
        code, out, journal = self.send_then_signal(job, signal.SIGTERM, 8, "--boot-wait", "8000")
        if code == 0:
            return self.record("A", False, f"the first run was not stopped: {tail(out)}")
        before = acks(journal)
        code, out = self.send(job, "--resume", "--journal", journal,
                              "--boot-wait", self.boot_wait)
        refused = code != 0 and "restarted" in out
        moved = acks(journal) != before
        self.record("A", refused and not moved,
                    f"resume with --boot-wait {self.boot_wait}: exit {code}, "
                    f"{'refused (restarted)' if refused else 'NOT refused'}, "
                    f"{'lines sent' if moved else 'nothing sent'}: {tail(out)}")

    def case_b(self):
        if self.resets:
            return self.skip("B", "the board resets when the port opens (case A covers it)")
        if not self.power_cycle:
            return self.skip("B", "GRBL_REAL_POWER_CYCLE is not set")
        job = self.job("b.gcode", strokes(12))
        code, out, journal = self.send_then_signal(job, signal.SIGTERM, 8)
        if code == 0:
            return self.record("B", False, f"the first run was not stopped: {tail(out)}")
        subprocess.run(self.power_cycle, shell=True, check=True)
        time.sleep(3.0)
        code, out = self.send(job, "--resume", "--journal", journal)
        refused = code != 0 and "journal" in out and "cannot resume" in out
        code2, out2 = self.send(job, "--resume", "--journal", journal, "--origin-confirmed")
        self.record("B", refused and code2 == 0,
                    f"resume: exit {code} ({'refused' if refused else 'NOT refused'}: "
                    f"{tail(out)}); with --origin-confirmed: exit {code2}")

    def case_c(self):
        square = lambda x: (f"G0 X{x} Y0\nG1 X{x + 4} Y0 F300\nG1 X{x + 4} Y4\n"
                            f"G1 X{x} Y4\nG1 X{x} Y0\n")
        text = "G21 G90\n" + square(0) + "M0\n" + square(6) + "G0 X0 Y0\n"
        job = self.job("c.gcode", text)
        journal = job + ".journal"
        code, out = self.send(job, "--journal", journal, "--on-pause", "abort")
        pause_line = 7  # the M0's line in the file
        paused = code != 0 and f"paused itself at line {pause_line} (`M0`)" in out
        executed = f"Last line known executed: line {pause_line}" in out
        flags = ["--resume", "--journal", journal, "--on-pause", "resume"]
        if self.resets:
            # The reset of opening the port loses the position; the work origin (G54, in
            # EEPROM) is where it was, which the operator confirms.
            flags.append("--origin-confirmed")
        code2, out2 = self.send(job, *flags)
        # The job's first 7 lines (G21 G90, the first square, the M0) ran before the pause.
        rest = "(7 done in earlier runs)" in out2
        first = "" if paused and executed else f" ({tail(out)})"
        self.record("C", paused and executed and code2 == 0 and rest,
                    f"abort at the pause: exit {code}, {'named' if paused else 'NOT named'}, "
                    f"{'lines up to the M0 executed' if executed else 'NOT all executed'}{first}; "
                    f"resume: exit {code2}, {'first square not sent again' if rest else tail(out2)}")

    def case_g92(self):
        if self.resets:
            return self.skip("G92", "the board resets when the port opens, which clears G92")
        p = self.port()
        p.command("G21 G90 G0 X3 Y4")
        p.wait_idle()
        p.command("G92 X0 Y0")
        p.close()
        job = self.job("g92.gcode", "G21 G90\nG1 X1 Y1 F300\n")
        code, out = self.send(job, "--journal", job + ".journal")
        p = self.port()
        st = p.status()
        p.command("G92.1")
        p.command("G0 X0 Y0")
        p.wait_idle()
        p.close()
        kept = "MPos:4.000,5.000" in st or "WPos:1.000,1.000" in st
        self.record("G92", code == 0 and kept, f"exit {code}, after the job: {st.strip()}")

    def case_hup(self):
        job = self.job("hup.gcode", strokes(12))
        code, out, journal = self.send_then_signal(job, signal.SIGHUP, 6)
        text = open(journal).read() if os.path.exists(journal) else ""
        off = "tool off (M5 M9), confirmed by $G" in text
        self.record("HUP", code != 0 and off,
                    f"exit {code}, journal {'says' if off else 'does NOT say'} tool off "
                    f"confirmed: {tail(out)}")

    def case_laser(self):
        if not self.laser_ok:
            return self.skip("LASER", "GRBL_REAL_LASER=1 is not set (the case sets $32=1)")
        p = self.port()
        settings = p.command("$$")
        was = "1" if "$32=1" in settings else "0"
        p.command("$32=1")
        p.close()
        # The arc's end is 9 mm from its centre, its start 1 mm: GRBL refuses it (error:33).
        text = ("(laser: needs $32=1)\nG21 G90\nM3 S300\nG1 X3 F300\nG1 X3 Y3\n"
                "G2 X10 Y0 I1 J0\nG1 X0 Y0\nM5\n")
        job = self.job("laser.gcode", text)
        code, out = self.send(job, "--journal", job + ".journal")
        text = open(job + ".journal").read()
        p = self.port()
        modal = p.command("$G")
        p.command(f"$32={was}")
        p.command("G0 X0 Y0")
        p.wait_idle()
        p.close()
        off = "tool off (M5 M9), confirmed by $G" in text and " M5 " in modal.replace("]", " ")
        self.record("LASER", code != 0 and "error:33" in out and off,
                    f"exit {code}, {'tool off, confirmed' if off else 'tool NOT confirmed off'}; "
                    f"$G after: {modal.strip()}")

    def run(self, only):
        cases = [("A", self.case_a), ("B", self.case_b), ("C", self.case_c),
                 ("G92", self.case_g92), ("HUP", self.case_hup), ("LASER", self.case_laser)]
        for name, f in cases:
            if only and name not in only:
                continue
            try:
                f()
            except Exception as e:  # a case that cannot run is a failure, named
                self.record(name, False, f"{type(e).__name__}: {e}")
        failed = [r for r in self.results if r[1] == "FAIL"]
        print(f"{len(self.results) - len(failed)} of {len(self.results)} cases passed or "
              f"skipped; work files in {self.dir}")
        return 1 if failed else 0


def strokes(n):
    """`n` 5 mm strokes at F300 (about a second each), pen up, from where the machine stands."""
    lines = ["G21 G90", "G0 Z0", "G0 X0 Y0"]
    for i in range(1, n + 1):
        lines.append(f"G1 X{i * 0.5:.3f} Y{5 if i % 2 else 0} F300")
    lines.append("G0 X0 Y0")
    return "\n".join(lines) + "\n"


def acks(journal):
    """Lines the journal records as answered (its `A` records)."""
    try:
        with open(journal) as f:
            return sum(1 for l in f if l.startswith("A "))
    except OSError:
        return 0


def tail(text, n=240):
    t = " ".join(text.split())
    return t if len(t) <= n else "…" + t[-n:]


def main():
    if not os.environ.get("GRBL_REAL_LINK"):
        print("GRBL_REAL_LINK is not set: no real controller to replay against, skipped")
        return 0
    only = {c.strip().upper() for c in os.environ.get("GRBL_REAL_CASES", "").split(",")
            if c.strip()}
    return Replay().run(only)


if __name__ == "__main__":
    sys.exit(main())
