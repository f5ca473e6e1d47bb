#!/usr/bin/env python3
"""A second, independent iRobot Create 1 Open Interface client for the hil tests (issue 18).

It shares nothing with the project's OI code (host/src/io/create_oi.cc): it is written from the
iRobot Create Open Interface manual (OI v2) and talks through pyserial (Debian's python3-serial),
which sets the port up with its own termios and ioctl calls. It drives the path it is given with
Drive (137) -- not the Drive Direct that crunchhost uses -- closed-loop on its own odometry from
the sensor stream, and prints one JSON line with what it saw:

  {"connected": true, "mode": 3, "packets": N, "corrupt": 0, "skipped_bytes": 0,
   "odometry": [x, y, theta], ...}

x, y in metres and theta in radians from where it started (+x ahead, counter-clockwise positive).
Exit status 0 when the whole path was driven; 1 with {"error": ...} otherwise.

Run it against the virtual robot as docs/CREATE.md says:

  crunch-virtual-robot --scene test/scenes/empty_arena.json --start 1 1 0 -- \
      python3 test/hil/create_oi_client.py --port {create}
"""
import argparse
import fcntl
import json
import math
import struct
import sys
import termios
import time

import serial  # python3-serial

# Opcodes (manual, "Open Interface Command Reference").
START, FULL, DRIVE, SENSORS, QUERY_LIST, STREAM, PAUSE_RESUME = 128, 132, 137, 142, 149, 148, 150
# Drive's special radii: straight, turn in place counter-clockwise.
RADIUS_STRAIGHT, RADIUS_CCW = 0x8000, 1
WHEEL_BASE_M = 0.258  # manual: "the wheels are 258 mm apart"
# Data bytes of the single packets 7..42 (manual, "Sensor Packets"); signed ones below.
SIZES = {i: 1 for i in range(7, 43)}
for i in (19, 20, 22, 23, 25, 26, 27, 28, 29, 30, 31, 33, 39, 40, 41, 42):
    SIZES[i] = 2
SIGNED = {19, 20, 23, 24, 39, 40, 41, 42}
HEADER = 19  # a stream frame: [19][n][id][data]...[checksum]
BUMPS, DISTANCE, ANGLE, OI_MODE = 7, 19, 20, 35


class Failure(Exception):
    pass


def i16(hi, lo):
    v = (hi << 8) | lo
    return v - 0x10000 if v & 0x8000 else v


def drive_bytes(velocity_mm_s, radius_mm):
    return struct.pack(">Bhh", DRIVE, velocity_mm_s,
                       radius_mm - 0x10000 if radius_mm >= 0x8000 else radius_mm)


class Client:
    def __init__(self, port, timeout_s):
        self.timeout_s = timeout_s
        try:
            self.ser = serial.Serial(port, baudrate=57600, bytesize=serial.EIGHTBITS,
                                     parity=serial.PARITY_NONE, stopbits=serial.STOPBITS_ONE,
                                     xonxoff=False, rtscts=False, timeout=0.05)
        except serial.SerialException as e:
            raise Failure("cannot open %s: %s" % (port, e))
        fd = self.ser.fileno()
        # What boost::asio's serial_port does before its first read, and pyserial's in_waiting:
        # both are plain ioctl() calls on a tty, and must work on the Create's port.
        try:
            fcntl.ioctl(fd, termios.FIONBIO, struct.pack("i", 1))
            fcntl.ioctl(fd, termios.FIONREAD, struct.pack("i", 0))
        except OSError as e:
            raise Failure("ioctl FIONBIO/FIONREAD on %s: %s" % (port, e))
        self.ser.reset_input_buffer()
        self.buf = bytearray()
        self.packets = 0
        self.corrupt = 0
        self.skipped = 0
        # Odometry: whole mm and whole degrees as the Create sends them, summed exactly.
        self.total_mm = 0
        self.total_deg = 0
        self.x = self.y = 0.0
        self.mode = None
        self.last_bumps = 0

    def send(self, data):
        self.ser.write(bytes(data))
        self.ser.flush()

    def read_exactly(self, n):
        """n bytes of a Sensors / Query List answer, within the timeout."""
        deadline = time.monotonic() + self.timeout_s
        out = bytearray()
        while len(out) < n:
            if time.monotonic() > deadline:
                raise Failure("no answer: %d of %d bytes within %.1f s" % (len(out), n,
                                                                           self.timeout_s))
            out += self.ser.read(max(1, min(n - len(out), self.ser.in_waiting)))
        return out

    def theta(self):
        return self.total_deg * math.pi / 180.0

    def apply(self, values):
        if DISTANCE in values and ANGLE in values:
            d = values[DISTANCE] / 1000.0
            mid = (self.total_deg + 0.5 * values[ANGLE]) * math.pi / 180.0
            self.x += d * math.cos(mid)
            self.y += d * math.sin(mid)
            self.total_mm += values[DISTANCE]
            self.total_deg += values[ANGLE]
        if OI_MODE in values:
            self.mode = values[OI_MODE]
        if BUMPS in values:
            self.last_bumps = values[BUMPS]

    def parse(self):
        """Takes every whole frame out of self.buf; returns the decoded ones."""
        frames = []
        while True:
            start = self.buf.find(bytes([HEADER]))
            if start < 0:
                self.skipped += len(self.buf)
                self.buf.clear()
                return frames
            self.skipped += start
            del self.buf[:start]
            if len(self.buf) < 2:
                return frames
            n = self.buf[1]
            if len(self.buf) < n + 3:
                return frames
            frame = self.buf[:n + 3]
            values = self.decode(frame)
            if values is None:
                # Not a frame (or a damaged one): drop its header and look again.
                self.corrupt += 1
                self.skipped += 1
                del self.buf[:1]
                continue
            del self.buf[:n + 3]
            self.packets += 1
            frames.append(values)

    @staticmethod
    def decode(frame):
        # The Create 1 makes the sum of every byte of the frame, header included, 0 mod 256
        # (the manual's own example, 19 5 29 2 25 13 0 163, sums to 256).
        if sum(frame) & 0xFF != 0 or frame[1] == 0:
            return None
        values, i, end = {}, 2, len(frame) - 1
        while i < end:
            pid = frame[i]
            size = SIZES.get(pid)
            if size is None or i + 1 + size > end:
                return None
            if size == 2:
                v = i16(frame[i + 1], frame[i + 2]) if pid in SIGNED else \
                    (frame[i + 1] << 8) | frame[i + 2]
            else:
                v = frame[i + 1] - 256 if pid in SIGNED and frame[i + 1] > 127 else frame[i + 1]
            values[pid] = v
            i += 1 + size
        return values

    def pump(self):
        """Reads what the stream brought (waiting at most the read timeout); applies it."""
        data = self.ser.read(max(1, self.ser.in_waiting))
        if data:
            self.last_data = time.monotonic()
            self.buf += data
        for values in self.parse():
            self.apply(values)
        if time.monotonic() - self.last_data > self.timeout_s:
            raise Failure("the sensor stream stopped (nothing for %.1f s)" % self.timeout_s)

    def run_until(self, done, what, limit_s):
        deadline = time.monotonic() + limit_s
        while not done():
            if time.monotonic() > deadline:
                raise Failure("%s: not done within %.1f s" % (what, limit_s))
            self.pump()

    def stop_and_settle(self, quiet_packets=8):
        """Drive 0 0, then reads until `quiet_packets` frames in a row report no motion."""
        self.send(drive_bytes(0, RADIUS_STRAIGHT))
        state = {"quiet": 0, "seen": self.packets, "mm": self.total_mm, "deg": self.total_deg}

        def settled():
            while state["seen"] < self.packets:
                state["seen"] += 1
                state["quiet"] += 1
            if self.total_mm != state["mm"] or self.total_deg != state["deg"]:
                state["quiet"] = 0
                state["mm"], state["deg"] = self.total_mm, self.total_deg
            return state["quiet"] >= quiet_packets

        self.run_until(settled, "stopping", 5.0)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--port", required=True, help="the Create's serial port")
    ap.add_argument("--leg", type=float, default=0.2, help="each straight leg, m")
    ap.add_argument("--speed", type=float, default=0.2, help="straight speed, m/s")
    ap.add_argument("--turn-deg", type=int, default=90, help="the turn, degrees (CCW)")
    ap.add_argument("--turn-rate", type=float, default=0.5, help="turn rate, rad/s")
    ap.add_argument("--probe-unsupported", action="store_true",
                    help="also ask for packet 100 in a Query List (no Create 1 has it)")
    ap.add_argument("--timeout", type=float, default=2.0, help="seconds without an answer")
    args = ap.parse_args()
    report = {"client": "pyserial %s" % serial.VERSION, "connected": False}
    client = None
    try:
        client = Client(args.port, args.timeout)
        client.send([START, FULL])
        client.send([SENSORS, OI_MODE])
        report["mode"] = client.read_exactly(1)[0]
        report["connected"] = True
        if report["mode"] != 3:
            raise Failure("Full mode asked, OI mode %d reported" % report["mode"])
        if args.probe_unsupported:
            # 100 is no Create 1 packet: the answer may carry only the mode's byte.
            client.send([QUERY_LIST, 2, 100, OI_MODE])
            report["probe_answer"] = list(client.read_exactly(1))
        client.send([STREAM, 4, BUMPS, DISTANCE, ANGLE, OI_MODE])
        client.last_data = time.monotonic()
        client.run_until(lambda: client.packets > 0, "first stream packet", args.timeout)

        leg_mm = int(round(args.leg * 1000))
        v = int(round(args.speed * 1000))
        wheel = int(round(args.turn_rate * WHEEL_BASE_M / 2 * 1000))  # mm/s of each wheel

        # Drive, turn, drive: each segment closed-loop on the Create's own odometry.
        mm0 = client.total_mm
        client.send(drive_bytes(v, RADIUS_STRAIGHT))
        client.run_until(lambda: client.total_mm - mm0 >= leg_mm, "first leg",
                         3 * args.leg / args.speed + 2)
        client.stop_and_settle()
        deg0 = client.total_deg
        client.send(drive_bytes(wheel, RADIUS_CCW))
        client.run_until(lambda: client.total_deg - deg0 >= args.turn_deg, "turn",
                         3 * math.radians(args.turn_deg) / args.turn_rate + 2)
        client.stop_and_settle()
        mm0 = client.total_mm
        client.send(drive_bytes(v, RADIUS_STRAIGHT))
        client.run_until(lambda: client.total_mm - mm0 >= leg_mm, "second leg",
                         3 * args.leg / args.speed + 2)
        client.stop_and_settle()
        client.send([PAUSE_RESUME, 0])
        client.send([START])  # back to Passive: the motors stay off
        report["mode_at_end"] = client.mode
        status = 0
    except Failure as e:
        report["error"] = str(e)
        status = 1
    if client is not None:
        report.update({"packets": client.packets, "corrupt": client.corrupt,
                       "skipped_bytes": client.skipped,
                       "odometry": [client.x, client.y, client.theta()],
                       "distance_mm": client.total_mm, "angle_deg": client.total_deg,
                       "bumps": client.last_bumps})
    print(json.dumps(report), flush=True)
    return status


if __name__ == "__main__":
    sys.exit(main())
