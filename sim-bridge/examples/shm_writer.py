#!/usr/bin/env python3
"""Write an aircraft pose into aerie's shared memory, the way a simulator would.

Dependency-free (Python 3.6+ standard library). Flies a level circle and writes one pose per
frame into /dev/shm/<name> (layout: sim-bridge/PROTOCOL.md, C header:
sim-bridge/include/aerie_pose.h). Watch it with:

    python3 sim-bridge/examples/shm_writer.py --seconds 10 &
    aerie listen --protocol shm --shm-name aerie-pose --seconds 5

The seqlock: `seq` is made odd, the fields and their CRC-32 (zlib.crc32 of bytes 16..136,
stored at offset 136) are written, `seq` is made even. CPython performs
these stores in program order and x86-64 keeps stores in order (TSO); on weakly ordered CPUs
(ARM) a Python writer has no memory fence available -- use the C header there.
"""

import argparse
import math
import mmap
import os
import struct
import time
import zlib

MAGIC = 0x53504541  # b"AEPS" read little-endian
VERSION = 2
SIZE = 144
FLAG_LOCAL_ENU = 1 << 0
FLAG_VELOCITY = 1 << 1
FLAG_RATES = 1 << 2

HEADER = struct.Struct("=IHH")  # offset 0: magic, version, size
SEQ = struct.Struct("=Q")  # offset 8: seqlock counter
# offset 16: flags, reserved, frame, sim time, position[3], attitude[3], velocity[3], rates[3]
BODY = struct.Struct("=IIQd3d3d3d3d")
CRC = struct.Struct("=II")  # offset 136: CRC-32 of bytes 16..136, reserved
assert 16 + BODY.size + CRC.size == SIZE

EARTH_RADIUS_M = 6371000.0  # spherical approximation, good enough for a demo path
G = 9.80665


class PoseWriter:
    """One writer of /dev/shm/<name> (or any path)."""

    def __init__(self, path):
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            if os.fstat(fd).st_size < SIZE:
                os.ftruncate(fd, SIZE)
            self.map = mmap.mmap(fd, SIZE)
        finally:
            os.close(fd)
        header = HEADER.unpack_from(self.map, 0)
        seq = SEQ.unpack_from(self.map, 8)[0] if header == (MAGIC, VERSION, SIZE) else 0
        self.seq = (seq + 1) & ~1  # continue an existing sequence, even = stable
        SEQ.pack_into(self.map, 8, self.seq)
        HEADER.pack_into(self.map, 0, MAGIC, VERSION, SIZE)

    def write(self, frame, sim_time_s, position, attitude_deg, velocity_enu=None,
              rates_deg_s=None, local_enu=False):
        """position: (lat deg, lon deg, alt m) or, with local_enu, (x, y, z) metres;
        attitude_deg: (heading, pitch, roll); velocity_enu: (east, north, up) m/s;
        rates_deg_s: (heading, pitch, roll) deg/s."""
        flags = (FLAG_LOCAL_ENU if local_enu else 0)
        flags |= FLAG_VELOCITY if velocity_enu is not None else 0
        flags |= FLAG_RATES if rates_deg_s is not None else 0
        body = BODY.pack(flags, 0, frame, sim_time_s, *position, *attitude_deg,
                         *(velocity_enu or (0.0, 0.0, 0.0)), *(rates_deg_s or (0.0, 0.0, 0.0)))
        self.seq += 1
        SEQ.pack_into(self.map, 8, self.seq)  # odd: writing
        self.map[16:16 + BODY.size] = body
        CRC.pack_into(self.map, 16 + BODY.size, zlib.crc32(body) & 0xFFFFFFFF, 0)
        self.seq += 1
        SEQ.pack_into(self.map, 8, self.seq)  # even: stable

    def close(self):
        self.map.close()


def circle_pose(t, lat0, lon0, alt, radius, speed):
    """A level clockwise circle around (lat0, lon0): pose, velocity and rates at time t."""
    omega = speed / radius  # rad/s
    a = omega * t
    east, north = radius * math.sin(a), radius * math.cos(a)
    lat = lat0 + math.degrees(north / EARTH_RADIUS_M)
    lon = lon0 + math.degrees(east / (EARTH_RADIUS_M * math.cos(math.radians(lat0))))
    heading = (math.degrees(a) + 90.0) % 360.0  # tangent, turning clockwise (right)
    roll = math.degrees(math.atan(speed * speed / (G * radius)))  # coordinated turn, right wing down
    v = (speed * math.cos(a), -speed * math.sin(a), 0.0)
    return (lat, lon, alt), (heading, 0.0, roll), v, (math.degrees(omega), 0.0, 0.0)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--name", default="aerie-pose",
                   help="file in /dev/shm, or a path containing '/' (default aerie-pose)")
    p.add_argument("--rate", type=float, default=60.0, help="poses per second (default 60)")
    p.add_argument("--seconds", type=float, default=10.0, help="how long to fly (default 10)")
    p.add_argument("--lat", type=float, default=47.26, help="circle centre latitude, deg")
    p.add_argument("--lon", type=float, default=11.35, help="circle centre longitude, deg")
    p.add_argument("--alt", type=float, default=3000.0, help="altitude, m above sea level")
    p.add_argument("--radius", type=float, default=3000.0, help="circle radius, m")
    p.add_argument("--speed", type=float, default=120.0, help="ground speed, m/s")
    args = p.parse_args()
    path = args.name if "/" in args.name else os.path.join("/dev/shm", args.name)

    w = PoseWriter(path)
    start = time.monotonic()
    frame = 0
    try:
        while True:
            t = frame / args.rate
            if t > args.seconds:
                break
            pos, att, vel, rates = circle_pose(t, args.lat, args.lon, args.alt, args.radius,
                                               args.speed)
            w.write(frame, t, pos, att, vel, rates)
            frame += 1
            delay = start + frame / args.rate - time.monotonic()
            if delay > 0:
                time.sleep(delay)
    except KeyboardInterrupt:
        pass
    finally:
        w.close()
    print("wrote %d poses to %s" % (frame, path))


if __name__ == "__main__":
    main()
