# SPDX-License-Identifier: GPL-3.0-or-later
"""facepuppet live: receive facepuppet's --stream in Blender (docs/osc.md, "Stream").

The face is shown live on the mesh imported from the same file the session deforms
(File > Import > Wavefront OBJ, or glTF; the vertex order must be the file's), and what is
received can be recorded as shape-key animation on the timeline: one shape key a scene
frame, keyed to 1 on its frame and 0 elsewhere (constant interpolation), placed by the
stream's timecode (the first one at the scene's start frame, its timecode in a timeline
marker and the scene's "facepuppet_timecode_in"), or by its time when it sends none. Where
two stream frames land on one scene frame (live frame times jitter, a timecode at another
rate) the scene frame keeps the later one: relative keys add, two at 1 would double the
face's motion. Stop shows the recording (the live key at 0); Record shows the live face
again (the live key at 1) and mutes the keys recorded before, which would add to it.

OSC is parsed with the standard library (socket, struct): Blender's Python has no liblo.
Install (Blender 3.4 as Debian ships it, and newer):
    blender --background --python-expr "import bpy; bpy.ops.preferences.addon_install(\
filepath='tools/blender/facepuppet_live.py', overwrite=True); \
bpy.ops.preferences.addon_enable(module='facepuppet_live'); bpy.ops.wm.save_userpref()"
Then View3D > Sidebar (N) > facepuppet: select the face, Connect (port 9100 by default:
`facepuppet live ... --stream osc:127.0.0.1:9100`; the address, 127.0.0.1 by default, takes
what facepuppet's bind= takes: listen_udp), Record, Stop.

The receiving part (StreamReceiver) needs no bpy: tests/link/test_blender.sh drives it in a
headless Blender (tests/link/blender_live_check.py).
"""

bl_info = {
    "name": "facepuppet live",
    "author": "facepuppet",
    "version": (1, 0, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > facepuppet",
    "description": "Receive facepuppet's live stream onto a face; record it as shape keys",
    "category": "Animation",
}

import socket
import struct
import sys

try:  # (Blender ships numpy: a frame of 26,719 vertices in well under a millisecond)
    import numpy as np
except ImportError:
    np = None

try:
    import bpy
    from bpy.props import BoolProperty, EnumProperty, IntProperty, StringProperty
except ImportError:  # (the receiver alone, outside Blender)
    bpy = None


# ---- OSC (the messages the stream sends: types i f d s b) -------------------------------

def _osc_string(p, at):
    end = p.index(b"\0", at)
    return p[at:end].decode("utf-8", "replace"), (end + 4) & ~3


def osc_decode(p):
    """(address, args) of one OSC message; ValueError when malformed."""
    try:
        address, at = _osc_string(p, 0)
        tags, at = _osc_string(p, at)
        if not tags.startswith(","):
            raise ValueError("no type tags")
        args = []
        for t in tags[1:]:
            if t == "i":
                args.append(struct.unpack_from(">i", p, at)[0]); at += 4
            elif t == "f":
                args.append(struct.unpack_from(">f", p, at)[0]); at += 4
            elif t == "d":
                args.append(struct.unpack_from(">d", p, at)[0]); at += 8
            elif t == "s":
                s, at = _osc_string(p, at); args.append(s)
            elif t == "b":
                n = struct.unpack_from(">i", p, at)[0]; at += 4
                args.append(bytes(p[at:at + n])); at += (n + 3) & ~3
            else:
                raise ValueError("type tag %r" % t)
        return address, args
    except (struct.error, IndexError) as e:
        raise ValueError(str(e))


def timecode_frames(tc, fps):
    """'HH:MM:SS:FF' (';' or '.' before FF: drop-frame, counted as non-drop here) at a whole
    fps into a frame count, or None."""
    try:
        hh, mm, ss, ff = tc.replace(";", ":").replace(".", ":").split(":")
        return ((int(hh) * 60 + int(mm)) * 60 + int(ss)) * fps + int(ff)
    except ValueError:
        return None


def _bound(family, addr, v6only=None):
    sock = socket.socket(family, socket.SOCK_DGRAM)
    try:
        if v6only is not None:
            sock.setsockopt(socket.IPPROTO_IPV6, socket.IPV6_V6ONLY, int(v6only))
        sock.bind(addr)
    except OSError:
        sock.close()
        raise
    sock.setblocking(False)
    return sock


def listen_udp(host, port):
    """Non-blocking UDP sockets listening on `host` at `port` (0: a free one) as facepuppet's
    bind= does (docs/osc.md, core/common/fp_net_listen.c): 127.0.0.1 or localhost, the
    IPv4 loopback and [::1] at the same port beside it where it can be bound; 0.0.0.0 or ::,
    every address, IPv4 and IPv6, through one [::] socket with IPV6_V6ONLY off (0.0.0.0 falls
    back to IPv4 alone, :: fails, where there is no IPv6); another IPv4 or IPv6 address
    (::1, [::1], fe80::1%eth0), that address alone. Returns (sockets, the addresses in words,
    "" or a warning). Raises ValueError for a name other than localhost, OSError where the
    address cannot be bound."""
    text = host[1:-1] if host.startswith("[") and host.endswith("]") else host
    if text == "localhost":
        text = "127.0.0.1"
    if ":" not in text:
        try:
            socket.inet_pton(socket.AF_INET, text)
        except OSError:
            raise ValueError("address %s: expected an IP address (127.0.0.1, 0.0.0.0, ::1, ::, "
                             "...) or localhost" % host) from None
        family = socket.AF_INET
    else:
        try:
            info = socket.getaddrinfo(text, port, socket.AF_INET6, socket.SOCK_DGRAM, 0,
                                      socket.AI_NUMERICHOST | socket.AI_PASSIVE)
        except socket.gaierror:
            raise ValueError("address %s: expected an IP address (127.0.0.1, 0.0.0.0, ::1, ::, "
                             "...) or localhost" % host) from None
        family, addr6 = socket.AF_INET6, info[0][4]
    warning = ""
    if text in ("0.0.0.0", "::") or (family == socket.AF_INET6 and
                                     socket.inet_pton(socket.AF_INET6, addr6[0]) == bytes(16)):
        try:
            sock = _bound(socket.AF_INET6, ("::", port), v6only=False)
            return [sock], "[::]:%d (IPv4 and IPv6)" % sock.getsockname()[1], ""
        except OSError as e:
            if family == socket.AF_INET6:
                raise
            warning = ("IPv6 senders are not heard: [::]:%d (IPv4 and IPv6) cannot be bound (%s); "
                       "listening on 0.0.0.0 (IPv4) alone" % (port, e.strerror))
    if family == socket.AF_INET6:
        sock = _bound(socket.AF_INET6, addr6, v6only=True)
        return [sock], "[%s]:%d" % (text, sock.getsockname()[1]), warning
    sock = _bound(socket.AF_INET, (text, port))
    port = sock.getsockname()[1]
    if text != "127.0.0.1":
        return [sock], "%s:%d" % (text, port), warning
    try:
        sock6 = _bound(socket.AF_INET6, ("::1", port), v6only=True)
    except OSError as e:
        return [sock], "127.0.0.1:%d" % port, (
            "[::1]:%d cannot be bound (%s): a sender whose localhost is ::1 is not heard; "
            "listening on 127.0.0.1 alone" % (port, e.strerror))
    return [sock, sock6], "127.0.0.1:%d and [::1]:%d" % (port, port), ""


class StreamReceiver:
    """The stream's state: the quantised offsets of every vertex, rebuilt from the packets of
    each frame; a frame is handed to on_frame(frame) once all its packets came, or a later
    frame's first one did (then frame["complete"] is False)."""

    RCVBUF = 4 << 20               # the socket receive buffer asked at least (bytes)
    KEY_BYTES_PER_VERTEX = 9       # a keyframe at its largest (docs/osc.md, "A receiver's buffer")

    def __init__(self, port, host="127.0.0.1", on_frame=None, rcvbuf=RCVBUF):
        self.rcvbuf_asked = rcvbuf
        self.socks, self.listening, bind_warning = listen_udp(host, port)
        self.sock = self.socks[0]
        self.rcvbuf, self.warning = self._ask_rcvbuf(rcvbuf)
        self.warning = "; ".join(w for w in (self.warning, bind_warning) if w)
        if self.warning:
            print("facepuppet live: " + self.warning)
        self.on_frame = on_frame
        self.info = None
        self.n = 0
        self.q = None              # array of 3n ints (the offsets in steps)
        self.current = None        # the frame being gathered
        self.frames = self.packets = self.bad = self.incomplete = 0
        self.last_seq = None
        self.lost = 0
        self.restarts = 0          # streams begun again (a sender's seq 0 after others)

    def _ask_rcvbuf(self, asked):
        """Ask for a receive buffer of `asked` bytes: a keyframe comes in one burst (about
        9 bytes a vertex), and what the buffer cannot hold while Blender is busy is lost
        until the next keyframe. Returns (bytes granted, "" or a warning)."""
        for sock in self.socks:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, asked)
        got = min(sock.getsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF) for sock in self.socks)
        if sys.platform.startswith("linux"):
            got //= 2  # (Linux doubles the value for its bookkeeping and reports the double)
        if got >= asked:
            return got, ""
        return got, ("the system granted a %d KiB socket receive buffer of the %d KiB asked: a "
                     "keyframe of more than about %d vertices comes in part while Blender is busy "
                     "(raise the limit: sysctl -w net.core.rmem_max=%d on Linux)"
                     % (got >> 10, asked >> 10, got // self.KEY_BYTES_PER_VERTEX, asked))

    def close(self):
        self.flush()
        for sock in self.socks:
            sock.close()

    def poll(self, max_packets=100000):
        """Read what has arrived (without blocking). Returns the packets read."""
        k = 0
        for sock in self.socks:
            while k < max_packets:
                try:
                    data = sock.recv(65536)
                except BlockingIOError:
                    break
                k += 1
                try:
                    self._packet(data)
                except ValueError:
                    self.bad += 1
        return k

    def flush(self):
        """Hand over the frame being gathered (the stream ended)."""
        if self.current is not None:
            self._emit(False)

    def _packet(self, data):
        address, args = osc_decode(data)
        self.packets += 1
        seq = args[0] & 0xffffffff
        if address == "/fp/stream/info" and seq == 0:
            self.last_seq = None  # a sender started (again): its count starts afresh
            self.restarts += self.packets > 1
        gap = None if self.last_seq is None else (seq - self.last_seq - 1) & 0xffffffff
        if gap is not None and gap >= 0x80000000:
            pass  # a packet older than the last one (reordered): neither lost nor the newest
        else:
            self.lost += gap or 0
            self.last_seq = seq
        if address == "/fp/stream/info":
            n, mmu, step, key, fps, crc, path = args[1:8]
            self.info = {"n": n, "mm_per_unit": mmu, "step": step, "key": key, "fps": fps,
                         "crc": crc & 0xffffffff, "path": path, "channels": list(args[8:])}
            if n != self.n:
                self.n = n
                self.q = np.zeros(3 * n, np.int32) if np else [0] * (3 * n)
            return
        if address != "/fp/stream/frame" or self.q is None:
            return  # (frames before the first info: nothing to rebuild them on)
        frame, flags, t, tc, part, parts, lo, hi, blob = args[1:10]
        if self.current is not None and self.current["frame"] != frame:
            self._emit(False)
        if self.current is None:
            self.current = {"frame": frame, "time": t, "timecode": tc, "parts": parts, "got": 0,
                            "channels": list(args[10:])}
        q = self.q
        count = struct.unpack_from(">I", blob, 0)[0]
        if len(blob) != 4 + 8 * count or not 0 <= lo <= hi <= self.n:
            raise ValueError("a malformed frame packet")
        if np is not None:
            if flags & 1:
                q[3 * lo:3 * hi] = 0
            rec = np.frombuffer(blob, np.dtype([("g", ">u2"), ("o", ">i2", 3)]), count, 4)
            v = lo + np.cumsum(rec["g"], dtype=np.int64)
            ok = v < hi
            q.reshape(-1, 3)[v[ok]] = rec["o"][ok]
        else:
            if flags & 1:
                for i in range(3 * lo, 3 * hi):
                    q[i] = 0
            v = lo
            for gap, x, y, z in struct.iter_unpack(">Hhhh", blob[4:4 + 8 * count]):
                v += gap
                if lo <= v < hi:
                    q[3 * v] = x
                    q[3 * v + 1] = y
                    q[3 * v + 2] = z
        self.current["got"] += 1
        if self.current["got"] == parts:
            self._emit(True)

    def _emit(self, complete):
        f = self.current
        self.current = None
        f["complete"] = complete
        self.frames += 1
        self.incomplete += not complete
        if self.on_frame:
            self.on_frame(f)

    def positions(self, neutral):
        """neutral (3n floats, mesh units) plus the offsets: 3n floats (numpy float32 when
        numpy is there, else a list)."""
        s = self.info["step"] / self.info["mm_per_unit"]
        q = self.q
        if np is not None:
            return (np.asarray(neutral, np.float64) + q * s).astype(np.float32)
        return [neutral[i] + q[i] * s for i in range(len(q))]


# ---- Blender: the face, live and recorded ----------------------------------------------

class FaceLink:
    """A receiver bound to an object: the live shape key shows each frame; while recording,
    each frame becomes a shape key keyed on its frame."""

    LIVE = "facepuppet live"

    def __init__(self, obj, port, align="TIMECODE", host="127.0.0.1"):
        self.obj = obj
        self.align = align
        self.recording = False
        self.recorded = []         # (scene frame, key name): one a scene frame
        self._at = {}              # scene frame -> its index in recorded
        self._stream_frame = []    # the stream frame each recorded key holds
        self.first_tc = None
        self.first_time = None
        self.start_frame = None
        self.error = ""
        mesh = obj.data
        self.neutral = (np.zeros(3 * len(mesh.vertices), np.float32) if np is not None
                        else [0.0] * (3 * len(mesh.vertices)))
        mesh.vertices.foreach_get("co", self.neutral)
        if mesh.shape_keys is None:
            obj.shape_key_add(name="Basis", from_mix=False)
        kb = mesh.shape_keys.key_blocks
        self.live = kb.get(self.LIVE) or obj.shape_key_add(name=self.LIVE, from_mix=False)
        self.live.value = 1.0
        # (a buffer for two keyframes of this face at their largest, 4 MiB at least)
        self.rx = StreamReceiver(port, host, on_frame=self._frame,
                                 rcvbuf=max(StreamReceiver.RCVBUF,
                                            2 * StreamReceiver.KEY_BYTES_PER_VERTEX * len(mesh.vertices)))

    def close(self):
        self.rx.close()

    def poll(self):
        return self.rx.poll()

    def _scene_frame(self, f, scene):
        fps = max(1, round(self.rx.info["fps"] or scene.render.fps))
        tcf = timecode_frames(f["timecode"], fps) if self.align == "TIMECODE" and f["timecode"] else None
        if self.start_frame is None:  # (the first frame recorded: the scene takes the stream's rate)
            scene.render.fps, scene.render.fps_base = fps, 1.0
            self.start_frame = scene.frame_start
            self.first_tc, self.first_time = tcf, f["time"]
            if f["timecode"]:
                scene["facepuppet_timecode_in"] = f["timecode"]
                scene.timeline_markers.new("fp " + f["timecode"], frame=self.start_frame)
        if tcf is not None and self.first_tc is not None:
            return self.start_frame + tcf - self.first_tc
        return self.start_frame + round((f["time"] - self.first_time) * fps)

    def _frame(self, f):
        if len(self.neutral) != 3 * self.rx.n:
            self.error = "the stream has %d vertices, %s has %d" % (self.rx.n, self.obj.name,
                                                                  len(self.neutral) // 3)
            return
        pos = self.rx.positions(self.neutral)
        self.live.data.foreach_set("co", pos)
        self.obj.data.update()
        if not self.recording:
            return
        scene = bpy.context.scene
        fr = self._scene_frame(f, scene)
        name = "fp %06d" % f["frame"]
        at = self._at.get(fr)
        if at is not None:
            # a second stream frame on this scene frame (frame times jitter, or the timecode
            # runs at another rate): relative keys add, so the scene frame keeps one key, the
            # latest stream frame's
            held, key_name = self.recorded[at]
            if self._stream_frame[at] > f["frame"]:
                return
            key = self.obj.data.shape_keys.key_blocks[key_name]
            key.data.foreach_set("co", pos)
            key.name = name
            self.recorded[at] = (fr, key.name)
            self._stream_frame[at] = f["frame"]
            return
        key = self.obj.shape_key_add(name=name, from_mix=False)
        key.data.foreach_set("co", pos)
        key.value = 0.0
        self._at[fr] = len(self.recorded)
        self._stream_frame.append(f["frame"])
        self.recorded.append((fr, key.name))

    def start(self):
        """Record from the next frame on, showing the live face: the live key back at 1 (Stop
        set it to 0 to show the recording) and the keys recorded before muted, so that they
        add nothing to it on the scene frames they hold (unmute them to play them again)."""
        self.recording = True
        self.recorded = []
        self._at = {}              # scene frame -> its index in recorded
        self._stream_frame = []    # the stream frame each recorded key holds
        self.start_frame = None
        for kb in self.obj.data.shape_keys.key_blocks:
            if kb.name.startswith("fp "):
                kb.mute = True
        self.live.value = 1.0

    def stop(self):
        """Key what was recorded: each key 1 on its frame, 0 on the frames around it."""
        self.rx.flush()
        self.recording = False
        key = self.obj.data.shape_keys
        if not self.recorded:
            return 0
        if key.animation_data is None:
            key.animation_data_create()
        if key.animation_data.action is None:
            key.animation_data.action = bpy.data.actions.new(self.obj.name + " facepuppet")
        action = key.animation_data.action
        self.recorded.sort()       # (one key a scene frame: _frame kept the latest on each)
        frames = [fr for fr, _ in self.recorded]
        for i, (fr, name) in enumerate(self.recorded):
            path = 'key_blocks["%s"].value' % name
            fc = action.fcurves.find(path) or action.fcurves.new(path)
            before = frames[i - 1] if i else fr - 1
            after = frames[i + 1] if i + 1 < len(frames) else fr + 1
            pts = [(before, 0.0), (fr, 1.0), (after, 0.0)]
            fc.keyframe_points.add(len(pts))
            fc.keyframe_points.foreach_set("co", [c for p in pts for c in p])
            for kp in fc.keyframe_points:
                kp.interpolation = "CONSTANT"
            fc.update()
        scene = bpy.context.scene
        scene.frame_start = min(frames)
        scene.frame_end = max(frames)
        self.live.value = 0.0
        return len(self.recorded)


if bpy is not None:
    _links = {}

    def _tick():
        for link in list(_links.values()):
            link.poll()
        return 1.0 / 120.0 if _links else None

    class FACEPUPPET_OT_connect(bpy.types.Operator):
        """Receive facepuppet's stream onto the active object"""
        bl_idname = "facepuppet.connect"
        bl_label = "Connect"
        port: IntProperty(name="Port", default=9100, min=1, max=65535)
        address: StringProperty(name="Address", default="127.0.0.1",
                                description="127.0.0.1 or localhost (and [::1] beside it), 0.0.0.0 or "
                                            ":: (every address, IPv4 and IPv6), or one IPv4 or IPv6 address")

        def execute(self, context):
            obj = context.active_object
            if obj is None or obj.type != "MESH":
                self.report({"ERROR"}, "select the face (the mesh imported from the session's file)")
                return {"CANCELLED"}
            try:
                link = FaceLink(obj, self.port, context.scene.facepuppet_align, self.address)
            except (OSError, ValueError) as e:
                self.report({"ERROR"}, "%s port %d: %s" % (self.address, self.port, e))
                return {"CANCELLED"}
            _links[obj.name] = link
            if not bpy.app.timers.is_registered(_tick):
                bpy.app.timers.register(_tick)
            return {"FINISHED"}

    class FACEPUPPET_OT_disconnect(bpy.types.Operator):
        bl_idname = "facepuppet.disconnect"
        bl_label = "Disconnect"

        def execute(self, context):
            for link in _links.values():
                link.close()
            _links.clear()
            return {"FINISHED"}

    class FACEPUPPET_OT_record(bpy.types.Operator):
        """Start recording what is received, or stop and key it on the timeline"""
        bl_idname = "facepuppet.record"
        bl_label = "Record"

        def execute(self, context):
            link = _links.get(context.active_object.name) if context.active_object else None
            if link is None:
                self.report({"ERROR"}, "connect first")
                return {"CANCELLED"}
            if link.recording:
                self.report({"INFO"}, "%d frames recorded" % link.stop())
            else:
                link.start()
            return {"FINISHED"}

    class FACEPUPPET_PT_panel(bpy.types.Panel):
        bl_space_type = "VIEW_3D"
        bl_region_type = "UI"
        bl_category = "facepuppet"
        bl_label = "facepuppet live"

        def draw(self, context):
            col = self.layout.column()
            link = _links.get(context.active_object.name) if context.active_object else None
            col.prop(context.scene, "facepuppet_align")
            if link is None:
                col.operator("facepuppet.connect")
                return
            rx = link.rx
            col.label(text="%d frames, %d packets lost" % (rx.frames, rx.lost))
            if link.error:
                col.label(text=link.error)
            if rx.warning:
                col.label(text="receive buffer %d KiB of %d KiB asked: keyframes may come in part"
                          % (rx.rcvbuf >> 10, rx.rcvbuf_asked >> 10), icon="ERROR")
            col.operator("facepuppet.record", text="Stop" if link.recording else "Record")
            col.operator("facepuppet.disconnect")

    _classes = (FACEPUPPET_OT_connect, FACEPUPPET_OT_disconnect, FACEPUPPET_OT_record, FACEPUPPET_PT_panel)

    def register():
        bpy.types.Scene.facepuppet_align = EnumProperty(
            name="Place by", items=[("TIMECODE", "Timecode", "the stream's timecodes"),
                                    ("TIME", "Time", "the stream's times")], default="TIMECODE")
        for c in _classes:
            bpy.utils.register_class(c)

    def unregister():
        for link in _links.values():
            link.close()
        _links.clear()
        for c in reversed(_classes):
            bpy.utils.unregister_class(c)
        del bpy.types.Scene.facepuppet_align
