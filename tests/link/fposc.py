"""Minimal OSC 1.0 encoding and decoding with the standard library (socket, struct), for the
tests of the control surface and the stream (docs/osc.md). Types: i f d s b (and T F N).
Also control_port: the port a `--control osc:0` process says it listens on."""
import re
import struct
import time


def _pad(b):
    return b + b"\0" * (4 - len(b) % 4)


def _blob(b):
    return struct.pack(">i", len(b)) + b + b"\0" * ((4 - len(b) % 4) % 4)


def encode(address, *args):
    """One OSC message. ints -> i, floats -> f, str -> s, bytes -> b; (tag, value) forces a tag."""
    tags, data = ",", b""
    for a in args:
        tag, v = a if isinstance(a, tuple) else (
            "i" if isinstance(a, int) else "f" if isinstance(a, float) else
            "s" if isinstance(a, str) else "b", a)
        tags += tag
        if tag == "i":
            data += struct.pack(">i", v)
        elif tag == "f":
            data += struct.pack(">f", v)
        elif tag == "d":
            data += struct.pack(">d", v)
        elif tag == "s":
            data += _pad(v.encode())
        elif tag == "b":
            data += _blob(v)
    return _pad(address.encode()) + _pad(tags.encode()) + data


def bundle(*messages, timetag=1):
    out = b"#bundle\0" + struct.pack(">Q", timetag)
    for m in messages:
        out += struct.pack(">i", len(m)) + m
    return out


def _string(p, at):
    end = p.index(b"\0", at)
    return p[at:end].decode("utf-8", "replace"), (end + 4) & ~3


def decode(p):
    """(address, [args]) of one OSC message (not a bundle); raises ValueError when malformed."""
    try:
        address, at = _string(p, 0)
        tags, at = _string(p, at)
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
            elif t == "t":  # a timetag: (seconds, fraction)
                args.append(struct.unpack_from(">II", p, at)); at += 8
            elif t == "s":
                s, at = _string(p, at); args.append(s)
            elif t == "b":
                n = struct.unpack_from(">i", p, at)[0]; at += 4
                args.append(bytes(p[at:at + n])); at += (n + 3) & ~3
            elif t in "TFN":
                args.append({"T": True, "F": False, "N": None}[t])
            else:
                raise ValueError("type tag %r" % t)
        return address, args
    except (struct.error, IndexError) as e:
        raise ValueError(str(e))


def control_port(p, err_path, timeout=120):
    """The port process p (started with --control osc:0, its stderr to the file err_path) says
    it listens on ("--control: listening on port N"), or None when it exits or the timeout
    passes first (the caller kills it and fails, with the file's text)."""
    t_end = time.time() + timeout
    while time.time() < t_end and p.poll() is None:
        with open(err_path) as f:
            m = re.search(r"--control: listening on port (\d+)", f.read())
        if m:
            return int(m.group(1))
        time.sleep(0.05)
    return None


def controller(port, timeout=10):
    """A control surface on 127.0.0.1:port: cmd(address, *args) sends one command and returns
    the arguments of its /fp/status reply; a result other than "ok" ends the test (sys.exit
    with the address and the result)."""
    import socket
    import sys
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.settimeout(timeout)

    def cmd(address, *args):
        s.sendto(encode(address, *args), ("127.0.0.1", port))
        while True:
            a, v = decode(s.recvfrom(65536)[0])
            if a == "/fp/status" and v[0] == address:
                if v[1] != "ok":
                    sys.exit("%s: %s" % (address, v[1]))
                return v
    return cmd
