#!/usr/bin/env python3
"""A test decoder of facepuppet's live output stream (docs/osc.md, "Stream"), written from
the document with the standard library only (fposc.py for OSC).

It receives the stream on a UDP port, rebuilds every frame (neutral + offsets), keeps track
of what it knows exactly (a range of vertices is stale once a packet covering it was lost,
until a keyframe packet covering it arrives or its vertices are sent again), and compares
each frame with the frames `facepuppet export --format pc2` wrote for the same take.

Usage: stream_decode.py --port P --obj MESH.obj --pc2 TAKE.pc2 [--clean-after F] [--timeout S]
Prints the figures, then "PASS" (exit 0) or "FAIL: ..." (exit 1):
  - frames received, lost (no packet of them arrived), packets lost (sequence gaps);
  - the largest error of a vertex the decoder holds exact, over every frame (must be within
    the stated precision: step x sqrt(3)/2, plus float rounding);
  - frames fully exact; with --clean-after F (the sender dropped packets only in its first F
    frames, FP_STREAM_DROP=P:F) every frame from the first keyframe at or after F on must be
    fully exact; without it and without drops, every frame must be.
"""
import argparse
import array
import math
import os
import select
import socket
import struct
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fposc  # noqa: E402


def load_obj_vertices(path):
    out = array.array("d")
    with open(path, "rb") as f:
        for line in f:
            if line.startswith(b"v "):
                x, y, z = line.split()[1:4]
                out.extend((float(x), float(y), float(z)))
    return out


def load_pc2(path):
    with open(path, "rb") as f:
        data = f.read()
    sig, ver, n, start, rate, frames = struct.unpack_from("<12siiffi", data, 0)
    if sig != b"POINTCACHE2\0":
        raise SystemExit("FAIL: %s is no PC2" % path)
    return n, frames, data, 32


class Decoder:
    """The stream's state: offsets (quantised), what is stale, and the frames rebuilt."""

    def __init__(self):
        self.n = None
        self.info = None
        self.q = None           # array('i') 3n: quantised offsets
        self.stale = None       # bytearray n: 1 = not known exactly
        self.frames = {}        # frame -> {"packets": [...], "key": bool, "time": t, "tc": s}
        self.last_seq = None
        self.seq_lost = 0
        self.packets = 0

    def on_packet(self, data):
        address, args = fposc.decode(data)
        self.packets += 1
        seq = args[0] & 0xffffffff
        if self.last_seq is not None and seq != (self.last_seq + 1) & 0xffffffff:
            self.seq_lost += (seq - self.last_seq - 1) & 0xffffffff
        self.last_seq = seq
        if address == "/fp/stream/info":
            n, mmu, step, key, fps, crc, path = args[1:8]
            self.info = {"n": n, "mm_per_unit": mmu, "step": step, "key": key, "fps": fps,
                         "crc": crc, "path": path, "channels": args[8:]}
            if self.n is None:
                self.n = n
                self.q = array.array("i", bytes(4 * 3 * n))
                self.stale = bytearray(b"\1" * n)
            return None
        if address != "/fp/stream/frame":
            raise SystemExit("FAIL: unknown address %s" % address)
        frame, flags, t, tc, part, parts, lo, hi, blob = args[1:10]
        return {"frame": frame, "key": flags & 1, "time": t, "tc": tc, "part": part,
                "parts": parts, "lo": lo, "hi": hi, "blob": blob, "channels": args[10:]}

    def apply(self, pk):
        """One packet of the frame being built; returns its range."""
        q, lo, hi = self.q, pk["lo"], pk["hi"]
        if pk["key"]:
            for i in range(3 * lo, 3 * hi):
                q[i] = 0
            self.stale[lo:hi] = bytes(hi - lo)
        v = lo
        blob = pk["blob"]
        count = struct.unpack_from(">I", blob, 0)[0]
        if len(blob) != 4 + 8 * count:
            raise SystemExit("FAIL: a blob of %d bytes says %d records" % (len(blob), count))
        for gap, x, y, z in struct.iter_unpack(">Hhhh", blob[4:]):
            v += gap
            if not lo <= v < hi:
                raise SystemExit("FAIL: a record at vertex %d outside its packet's range [%d, %d)" % (v, lo, hi))
            q[3 * v], q[3 * v + 1], q[3 * v + 2] = x, y, z
            self.stale[v] = 0
        return lo, hi

    def finish_frame(self, got_ranges):
        """After a frame's packets: the ranges no packet covered are stale."""
        at = 0
        for lo, hi in sorted(got_ranges):
            if lo > at:
                self.stale[at:lo] = b"\1" * (lo - at)
            at = max(at, hi)
        if at < self.n:
            self.stale[at:self.n] = b"\1" * (self.n - at)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--port", type=int, required=True)
    ap.add_argument("--obj", required=True)
    ap.add_argument("--pc2", required=True)
    ap.add_argument("--clean-after", type=int, default=None)
    ap.add_argument("--lossy", action="store_true",
                    help="drops all along: only the vertices held exact must be")
    ap.add_argument("--timeout", type=float, default=120)
    a = ap.parse_args()
    neutral = load_obj_vertices(a.obj)
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 8 << 20)
    sock.bind(("127.0.0.1", a.port))
    print("listening on %d (receive buffer %d bytes)" % (a.port, sock.getsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF)),
          flush=True)
    raw = []
    t_end = time.time() + a.timeout
    last = None
    while time.time() < t_end:
        wait = 3.0 if raw else t_end - time.time()
        if not select.select([sock], [], [], max(0.0, wait))[0]:
            if raw:
                break
            continue
        raw.append(sock.recv(65536))
    if not raw:
        print("FAIL: nothing received")
        return 1
    npc, nframes, pc2, pc2_at = load_pc2(a.pc2)   # (after: a run writes it as it streams)
    d = Decoder()
    per_frame = {}
    order = []
    for data in raw:   # (the packets in arrival order; a frame's packets are consecutive)
        pk = d.on_packet(data)
        if pk is None:
            continue
        f = pk["frame"]
        if f not in per_frame:
            per_frame[f] = []
            order.append(f)
        per_frame[f].append(pk)
    if d.n is None:
        print("FAIL: no /fp/stream/info arrived")
        return 1
    if d.n != npc or len(neutral) != 3 * d.n:
        print("FAIL: %d vertices streamed, %d in the PC2, %d in the OBJ" % (d.n, npc, len(neutral) // 3))
        return 1
    step, mmu = d.info["step"], d.info["mm_per_unit"]
    tol_mm = step * math.sqrt(3) / 2 + 1e-3    # (float32 positions of a face in 10 mm units)
    scale = step / mmu
    print("info: %d vertices, %.4g mm per unit, step %.3g mm (a vertex within %.3g mm), keyframe "
          "every %d frames, channels %s" % (d.n, mmu, step, step * math.sqrt(3) / 2, d.info["key"],
                                            list(d.info["channels"])))
    worst = 0.0
    exact_frames = lost_frames = 0
    bad = []
    clean_from = None
    first = order[0]
    expect = range(first, first + nframes)
    for f in expect:
        pks = per_frame.get(f, [])
        if not pks:
            lost_frames += 1
            d.stale[:] = b"\1" * d.n
        ranges = [d.apply(pk) for pk in pks]
        d.finish_frame(ranges)
        key = any(pk["key"] for pk in pks)
        if a.clean_after is not None and clean_from is None and key and f - first >= a.clean_after:
            clean_from = f
        base = pc2_at + (f - first) * d.n * 12
        if base + d.n * 12 > len(pc2):
            print("FAIL: frame %d beyond the PC2's %d frames" % (f, nframes))
            return 1
        pos = struct.unpack_from("<%df" % (3 * d.n), pc2, base)
        q, stale = d.q, d.stale
        frame_worst, all_exact = 0.0, True
        for v in range(d.n):
            if stale[v]:
                all_exact = False
                continue
            i = 3 * v
            dx = neutral[i] + q[i] * scale - pos[i]
            dy = neutral[i + 1] + q[i + 1] * scale - pos[i + 1]
            dz = neutral[i + 2] + q[i + 2] * scale - pos[i + 2]
            e = math.sqrt(dx * dx + dy * dy + dz * dz) * mmu
            if e > frame_worst:
                frame_worst = e
        worst = max(worst, frame_worst)
        if frame_worst > tol_mm:
            bad.append((f, frame_worst))
        exact_frames += all_exact
        if not all_exact and not a.lossy and (a.clean_after is None or (clean_from is not None and f >= clean_from)):
            bad.append((f, "stale %d vertices" % sum(stale)))
    extra = [f for f in order if f not in expect]
    print("received %d packets of %d frames (expected %d); frames lost %d; packets lost (sequence "
          "gaps) %d" % (d.packets, len(order), nframes, lost_frames, d.seq_lost))
    print("largest error of a vertex held exact: %.4f mm (allowed %.4f mm); frames fully exact %d of %d%s"
          % (worst, tol_mm, exact_frames, nframes,
             "" if clean_from is None else "; clean from frame %d (first keyframe after the drops) on" % (clean_from - first)))
    if extra:
        print("FAIL: frames beyond the take: %s" % extra[:5])
        return 1
    if bad:
        print("FAIL: %d frames not exact, e.g. %s" % (len(bad), bad[:5]))
        return 1
    if a.clean_after is None and not a.lossy and (lost_frames or d.seq_lost):
        print("FAIL: loss on loopback without drops")
        return 1
    if a.clean_after is not None and clean_from is None:
        print("FAIL: no keyframe after the drops")
        return 1
    print("PASS")
    return 0


if __name__ == "__main__":
    sys.exit(main())
