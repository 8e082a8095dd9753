#!/usr/bin/env python3
"""A serial link to a GRBL controller that runs as a program (grbl-sim built from GRBL 1.1h):
a pseudo-terminal a sender opens like a USB serial adapter, with what a real board adds.

* Bytes are paced at the baud rate (10 bits a byte) both ways.
* Opening the port resets the controller, as the DTR pulse resets an Arduino Uno
  (`--no-reset-on-open`: a board with auto-reset disabled). A reset restarts the program: the
  position and G92 are lost, settings kept (grbl-sim keeps its EEPROM in EEPROM.DAT in the
  working directory).
* After a reset the banner comes `--boot-ms` later, as after a bootloader, and what the sender
  writes meanwhile is lost.
* SIGUSR1 power-cycles the controller (the same restart), whether a client is connected or not.

Standard library only (Linux). Usage:

    link.py --link /tmp/ttyGRBL [--baud 115200] [--boot-ms 0] [--no-reset-on-open]
            [--workdir DIR] -- ./grbl_sim.exe -n -s /dev/null -b block.out

`{run}` in the command is replaced by the number of the controller's start (0, 1, ...), so each
start can write its own block log. The link's pid is written to DIR/link.pid; SIGTERM or
SIGINT stop it.
"""

import argparse
import os
import pty
import select
import signal
import subprocess
import sys
import time
import tty


class Controller:
    """The controller program, started and restarted (a reset or a power cycle)."""

    def __init__(self, argv, workdir, boot_ms):
        self.argv = argv
        self.workdir = workdir
        self.boot_ms = boot_ms
        self.proc = None
        self.runs = 0
        self.ready_at = None  # monotonic time the program (re)starts; None: running

    def reset(self):
        """Stops the program; it starts again after the boot delay."""
        if self.proc is not None:
            self.proc.kill()
            self.proc.wait()
            self.proc = None
        self.ready_at = time.monotonic() + self.boot_ms / 1000.0

    def tick(self):
        """Starts the program when its boot delay is over."""
        if self.proc is None and self.ready_at is not None and time.monotonic() >= self.ready_at:
            argv = [a.replace("{run}", str(self.runs)) for a in self.argv]
            self.runs += 1
            self.proc = subprocess.Popen(
                argv,
                cwd=self.workdir,
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                bufsize=0,
            )
            os.set_blocking(self.proc.stdout.fileno(), False)
            self.ready_at = None

    def stop(self):
        if self.proc is not None:
            self.proc.kill()
            self.proc.wait()
            self.proc = None


def client_connected(master):
    """Whether a client holds the pseudo-terminal's other end open (no POLLHUP on the master)."""
    p = select.poll()
    p.register(master, select.POLLIN | select.POLLHUP)
    return not any(ev & select.POLLHUP for _, ev in p.poll(0))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--link", required=True, help="symlink to create to the pseudo-terminal")
    ap.add_argument("--baud", type=int, default=115200)
    ap.add_argument("--boot-ms", type=int, default=0)
    ap.add_argument("--no-reset-on-open", action="store_true")
    ap.add_argument("--workdir", default=".")
    ap.add_argument("command", nargs=argparse.REMAINDER)
    a = ap.parse_args()
    argv = a.command[1:] if a.command[:1] == ["--"] else a.command
    if not argv:
        ap.error("the controller's command is missing (after --)")
    if a.baud <= 0 or a.boot_ms < 0:
        ap.error("--baud must be positive and --boot-ms not negative")
    workdir = os.path.abspath(a.workdir)
    os.makedirs(workdir, exist_ok=True)

    master, slave = pty.openpty()
    tty.setraw(slave)
    name = os.ttyname(slave)
    os.close(slave)  # the client opens it; the master sees POLLHUP while nobody does
    os.set_blocking(master, False)
    if os.path.lexists(a.link):
        os.unlink(a.link)
    os.symlink(name, a.link)
    with open(os.path.join(workdir, "link.pid"), "w") as f:
        f.write(f"{os.getpid()}\n")

    ctl = Controller(argv, workdir, a.boot_ms)
    ctl.reset()
    events = {"power": False, "stop": False}
    signal.signal(signal.SIGUSR1, lambda *_: events.__setitem__("power", True))
    for s in (signal.SIGTERM, signal.SIGINT, signal.SIGHUP):
        signal.signal(s, lambda *_: events.__setitem__("stop", True))
    print(f"{a.link} -> {name}", flush=True)

    byte_s = 10.0 / a.baud
    to_ctl, to_client = bytearray(), bytearray()
    next_in = next_out = time.monotonic()
    connected = False
    try:
        while not events["stop"]:
            now = time.monotonic()
            if events["power"]:
                events["power"] = False
                print("power cycle", file=sys.stderr, flush=True)
                ctl.reset()
                to_ctl.clear()
                to_client.clear()
            was, connected = connected, client_connected(master)
            if connected and not was:
                # The client opened the port: a DTR pulse.
                if not a.no_reset_on_open:
                    ctl.reset()
                to_ctl.clear()
                to_client.clear()
            ctl.tick()
            # Client -> controller, lost while the controller boots.
            if connected:
                try:
                    data = os.read(master, 4096)
                    if ctl.proc is not None:
                        to_ctl += data
                except (BlockingIOError, OSError):
                    pass
            while to_ctl and next_in <= now and ctl.proc is not None:
                try:
                    ctl.proc.stdin.write(bytes(to_ctl[:1]))
                except BrokenPipeError:
                    break
                del to_ctl[:1]
                next_in = max(next_in + byte_s, now - byte_s)
            # Controller -> client, unheard while nobody listens.
            if ctl.proc is not None:
                try:
                    data = ctl.proc.stdout.read(4096)
                    if data and connected:
                        to_client += data
                except (BlockingIOError, TypeError):
                    pass
            while to_client and next_out <= now:
                try:
                    os.write(master, bytes(to_client[:1]))
                except (BlockingIOError, OSError):
                    break
                del to_client[:1]
                next_out = max(next_out + byte_s, now - byte_s)
            time.sleep(0.0005)
    finally:
        ctl.stop()
        if os.path.islink(a.link):
            os.unlink(a.link)
    return 0


if __name__ == "__main__":
    sys.exit(main())
