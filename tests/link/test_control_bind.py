#!/usr/bin/env python3
"""--control's bind= takes what the osc input's bind= takes (docs/osc.md, Control; fp_net.h,
fp_udp_listen): for each address a headless `run --control osc:0,bind=ADDR` (the port picked
by the system, read from its "listening on port" line) is asked /fp/status from an IPv4 and an
IPv6 loopback client, and each client that the address should hear gets its reply from the
control port:
  127.0.0.1 and localhost: 127.0.0.1 and [::1] (where the machine has an IPv6 loopback);
  ::1 and [::1]: [::1];  0.0.0.0 and ::: both, on one dual-stack socket, with the warning
  that OSC has no authentication;
and bind=bogus, bind=1.2.3 are refused before the run starts (exit 64), naming the address.
Before: every IPv6 address and localhost was refused ("expected an IPv4 address", exit 64),
and on 0.0.0.0 no IPv6 client was heard.
Usage: test_control_bind.py FACEPUPPET_BIN PLUGIN_DIR MESH RECORDING WORK_DIR
Prints "PASS" last on success; exit 1 with "FAIL: ..." otherwise."""
import os
import re
import atexit
import select
import shutil
import socket
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fposc  # noqa: E402

fp, plugdir, mesh, rec, work = (os.path.abspath(a) for a in sys.argv[1:6])
work = tempfile.mkdtemp(prefix="fp-control-bind-", dir=work)  # the runs' cwd: their outputs
atexit.register(shutil.rmtree, work, True)


def fail(msg):
    print("FAIL: " + msg)
    sys.exit(1)


def have_ipv6():
    try:
        with socket.socket(socket.AF_INET6, socket.SOCK_DGRAM) as s:
            s.bind(("::1", 0))
        return True
    except OSError:
        return False


def start(bind):
    err_path = os.path.join(work, "bind.err")
    err = open(err_path, "w")
    p = subprocess.Popen([fp, "run", "--plugin-dir", plugdir, "--mesh", mesh, "--input",
                          "replay:%s,loop=1" % rec, "--control", "osc:0,bind=%s" % bind,
                          "--duration", "120", "-q"], stdout=subprocess.DEVNULL, stderr=err, cwd=work)
    t_end = time.time() + 120
    while time.time() < t_end:
        text = open(err_path).read()
        m = re.search(r"--control: listening on port (\d+)", text)
        if m:
            return p, int(m.group(1)), text
        if p.poll() is not None:
            fail("bind=%s: the run ended (exit %s) before listening:\n%s" % (bind, p.returncode, text))
        time.sleep(0.1)
    p.kill()
    fail("bind=%s: the run did not listen in 120 s" % bind)


def status_from(family, host, port):
    """/fp/status sent from a client on host: the reply's result, or None when unanswered."""
    with socket.socket(family, socket.SOCK_DGRAM) as s:
        s.bind((host, 0))
        s.sendto(fposc.encode("/fp/status"), (host, port))
        if not select.select([s], [], [], 3)[0]:
            return None
        data, sender = s.recvfrom(65536)
        address, args = fposc.decode(data)
        if address != "/fp/status" or sender[1] != port:
            fail("from %s: answered %r from %r" % (host, address, sender))
        return args[1]


v6 = have_ipv6()
cases = [("127.0.0.1", True, v6, False), ("localhost", True, v6, False), ("::1", False, True, False),
         ("[::1]", False, True, False), ("0.0.0.0", True, v6, True), ("::", True, True, True)]
for bind, hears4, hears6, warns in cases:
    if not v6 and ":" in bind:
        print("  bind=%-10s (no IPv6 loopback here: not checked)" % bind)
        continue
    p, port, text = start(bind)
    try:
        got4 = status_from(socket.AF_INET, "127.0.0.1", port)
        got6 = status_from(socket.AF_INET6, "::1", port) if v6 else None
    finally:
        with socket.socket(socket.AF_INET6 if ":" in bind else socket.AF_INET, socket.SOCK_DGRAM) as q:
            q.sendto(fposc.encode("/fp/quit"), ("::1" if ":" in bind else "127.0.0.1", port))
        try:
            rc = p.wait(30)
        except subprocess.TimeoutExpired:
            p.kill()
            fail("bind=%s: /fp/quit did not end the run" % bind)
    print("  bind=%-10s port %5d: from 127.0.0.1 %-4s from [::1] %-4s %s" %
          (bind, port, got4, got6, "(warned)" if "no authentication" in text else ""))
    if rc != 0:
        fail("bind=%s: exit %d" % (bind, rc))
    if (got4 == "ok") != hears4:
        fail("bind=%s: from 127.0.0.1 %s, wanted %s" % (bind, got4, "ok" if hears4 else "no reply"))
    if v6 and (got6 == "ok") != hears6:
        fail("bind=%s: from [::1] %s, wanted %s" % (bind, got6, "ok" if hears6 else "no reply"))
    if ("no authentication" in text) != warns:
        fail("bind=%s: the warning %s:\n%s" % (bind, "missing" if warns else "given", text))

for bad in ["bogus", "1.2.3", "::g"]:
    r = subprocess.run([fp, "run", "--plugin-dir", plugdir, "--mesh", mesh, "--input",
                        "replay:%s" % rec, "--control", "osc:0,bind=%s" % bad],
                       stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, cwd=work)
    line = r.stderr.strip().splitlines()[-1] if r.stderr.strip() else ""
    print("  bind=%-10s exit %d: %s" % (bad, r.returncode, line))
    if r.returncode != 64 or "bind=%s" % bad not in line or "expected an IP address" not in line:
        fail("bind=%s: wanted exit 64 naming it" % bad)
print("PASS")
