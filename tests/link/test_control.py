#!/usr/bin/env python3
"""A headless `facepuppet run` driven entirely over OSC from loopback (issue 55, item 1).

The run plays a real recording (looped) through the anchored mapping with auto=0, so that
only the control surface engages and commits, records takes in a folder and listens on
--control osc:PORT. This client (the standard library's socket and struct: fposc.py):
  1. asks the status (idle, not recording); sends four bad bundles each holding /fp/engage
     (an element of length 0 after it, 2 stray bytes after the bundle, a cut message, a NaN
     radius): none answered, each counted once, still idle; a good bundle's two messages
     both answered in order; subscribes;
  2. /fp/record/start scene7 12, /fp/engage, /fp/commit (as a button: 0.0 let go does
     nothing, unanswered; 1.0 pressed commits), /fp/record/stop: every command
     answered by /fp/status naming it, "ok", and the state after it (recording 1 with
     slate scene7 and take 12, engaged, committed, recording 0);
  3. the same take number again is refused ("error: ... exists"), /fp/play too (run has no
     transport), /fp/undo and /fp/radius answered; every finite radius outside the range
     (0, negative, 1e6, 1e300, 1e-7) answered "error: radius ... outside [";
  4. Live Link Face's /Slate, /Take, /RecordStart llf 3 and /RecordStop: the same; then
     /fp/record/start and /fp/record/stop as buttons (0.0 nothing, 1.0 take llf 5);
  5. 10,000 hostile packets (random bytes, cut messages, wrong types, NaN and infinite
     values, slates and mappings with paths, nested and broken bundles, unknown addresses):
     each counted as refused (the status's refused count grows by exactly the messages
     sent), none answered, and the status after them is the status before (state, slate,
     take, recording); the takes folder holds the same files;
  6. from [::1] (a sender whose "localhost" resolved to IPv6 first; where the machine has an
     IPv6 loopback): /fp/status answered to that sender, from the control port;
  7. /fp/quit: the run ends (exit 0) with 1 engage and 1 commit in its summary.
Then the shell wrapper checks the takes (facepuppet takes --json, play).
Usage: test_control.py FACEPUPPET_BIN PLUGIN_DIR MESH RECORDING TAKE_DIR WORK_DIR
Prints "PASS" last on success; exit 1 with "FAIL: ..." otherwise."""
import os
import random
import select
import socket
import struct
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fposc  # noqa: E402

fp, plugdir, mesh, rec, takes, work = sys.argv[1:7]


def fail(msg):
    print("FAIL: " + msg)
    sys.exit(1)


def start_run():
    for _ in range(5):
        port = random.randint(20000, 60000)
        err = open(os.path.join(work, "run.err"), "w")
        out = open(os.path.join(work, "run.out"), "w")
        p = subprocess.Popen([fp, "run", "--plugin-dir", plugdir, "--mesh", mesh,
                              "--input", "replay:%s,loop=1" % rec, "--mapping", "anchored,auto=0",
                              "--take-dir", takes, "--control", "osc:%d" % port,
                              "--duration", "200", "--out", os.path.join(work, "out.obj")],
                             stdout=out, stderr=err)
        t_end = time.time() + 120
        while time.time() < t_end:
            text = open(os.path.join(work, "run.err")).read()
            if "--control: listening on port" in text:
                return p, port
            if p.poll() is not None:
                break
            time.sleep(0.1)
        if p.poll() is None:
            p.kill()
            fail("the run did not listen in 120 s")
        if "cannot listen" not in open(os.path.join(work, "run.err")).read():
            print(open(os.path.join(work, "run.err")).read())
            fail("the run ended (%s) before listening" % p.returncode)
    fail("no free port in 5 tries")


run, port = start_run()
sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
sock.bind(("127.0.0.1", 0))
target = ("127.0.0.1", port)
pushes = []


def receive(timeout):
    """The next /fp/status message within timeout, or None; pushes are kept aside."""
    end = time.time() + timeout
    while True:
        left = end - time.time()
        if left <= 0 or not select.select([sock], [], [], left)[0]:
            return None
        data, _ = sock.recvfrom(65536)
        address, args = fposc.decode(data)
        if address != "/fp/status":
            fail("a reply to %s, not /fp/status" % address)
        st = dict(zip(["command", "result", "state", "timecode", "slate", "take", "recording",
                       "time", "frame", "refused"], args))
        if st["command"] == "push":
            pushes.append(st)
            continue
        return st


replies = 0


def command(address, *args, expect="ok"):
    global replies
    sock.sendto(fposc.encode(address, *args), target)
    st = receive(10)
    if st is None:
        fail("%s got no reply in 10 s" % address)
    if st["command"] != address:
        fail("%s answered as %s" % (address, st["command"]))
    if not st["result"].startswith(expect):
        fail("%s answered %r, wanted %r" % (address, st["result"], expect))
    replies += 1
    print("  %-18s %-40s -> %s" % (address, " ".join(str(a) for a in args),
                                   {k: st[k] for k in ("result", "state", "slate", "take", "recording", "timecode")}))
    return st


def want(st, **kv):
    for k, v in kv.items():
        if st[k] != v:
            fail("status %s = %r, wanted %r (%r)" % (k, st[k], v, st))


def ipv6_status():
    """/fp/status from an IPv6 loopback socket: answered there, or None without IPv6."""
    try:
        s6 = socket.socket(socket.AF_INET6, socket.SOCK_DGRAM)
        s6.bind(("::1", 0))
    except OSError as e:
        print("  (no IPv6 loopback here: %s; [::1] not checked)" % e)
        return None
    with s6:
        s6.sendto(fposc.encode("/fp/status"), ("::1", port))
        if not select.select([s6], [], [], 10)[0]:
            fail("/fp/status from [::1] got no reply in 10 s (--control hears 127.0.0.1 only)")
        data, sender = s6.recvfrom(65536)
        address, args = fposc.decode(data)
        if address != "/fp/status" or args[0] != "/fp/status" or sender[1] != port:
            fail("/fp/status from [::1] answered %r %r from %r" % (address, args[:2], sender))
        print("  %-18s %-40s -> %s" % ("/fp/status", "(from [::1])", args[1]))
        return args


try:
    st = command("/fp/status")
    want(st, state="idle", recording=0)
    if "[::1] too" in open(os.path.join(work, "run.err")).read():
        ipv6_status()
    elif socket.has_ipv6:
        try:
            probe = socket.socket(socket.AF_INET6, socket.SOCK_DGRAM)
            probe.bind(("::1", 0))
            probe.close()
            fail("the machine has an IPv6 loopback, but --control did not listen on [::1]")
        except OSError:
            print("  (no IPv6 loopback here; [::1] not checked)")
    # a bad bundle is refused whole: nothing in it applies nor is answered, counted once
    # (malformed), even where its first element is a good message (OSC 1.0: a bundle's
    # messages take effect together)
    for name, p in [("an element of length 0",
                     fposc.bundle(fposc.encode("/fp/engage")) + struct.pack(">i", 0)),
                    ("2 stray bytes after it", fposc.bundle(fposc.encode("/fp/engage")) + b"\0\0"),
                    ("a cut message after it",
                     fposc.bundle(fposc.encode("/fp/engage"), fposc.encode("/fp/radius", 2.0)[:-4])),
                    ("a refused message in it",
                     fposc.bundle(fposc.encode("/fp/engage"), fposc.encode("/fp/radius", float("nan"))))]:
        refused0 = command("/fp/status")["refused"]
        sock.sendto(p, target)
        got = receive(0.7)
        if got is not None:
            fail("a bundle with %s was answered: %r %r" % (name, got["command"], got["result"]))
        st = command("/fp/status")
        if st["refused"] != refused0 + 1:
            fail("a bundle with %s: refused %d -> %d, wanted +1" % (name, refused0, st["refused"]))
        time.sleep(0.3)
        want(command("/fp/status"), state="idle")
        print("  a bundle with %s: refused whole, unanswered, still idle" % name)
    bad_bundles = 4
    # a good bundle's messages all apply, each answered in order
    sock.sendto(fposc.bundle(fposc.encode("/fp/status"), fposc.encode("/fp/radius", 2.5)), target)
    got = [receive(5), receive(5)]
    if [g and (g["command"], g["result"]) for g in got] != [("/fp/status", "ok"), ("/fp/radius", "ok")]:
        fail("a good bundle of /fp/status and /fp/radius answered %r" % got)
    command("/fp/subscribe")
    st = command("/fp/record/start", "scene7", 12)
    want(st, recording=1, slate="scene7", take=12)
    time.sleep(0.3)
    st = command("/fp/engage")
    time.sleep(0.5)
    want(command("/fp/status"), state="engaged", recording=1)
    # a control surface's button (TouchOSC, Open Stage Control): its value 0 as it is let go
    # does nothing and is not answered (nor refused), its value 1 as it is pressed commits
    sock.sendto(fposc.encode("/fp/commit", 0.0), target)
    if receive(0.5) is not None:
        fail("a button let go (/fp/commit 0.0) was answered")
    want(command("/fp/status"), state="engaged", recording=1, refused=bad_bundles)
    command("/fp/commit", 1.0)
    time.sleep(0.3)
    want(command("/fp/status"), state="committed", recording=1, take=12)
    st = command("/fp/record/stop")
    want(st, recording=0, take=12, slate="scene7")
    command("/fp/record/start", "scene7", 12, expect="error")
    # /fp/take of a number that exists is refused at once, naming the take and the next free
    # number (before: "ok", and the /fp/record/start after it refused); that start then takes
    # the next free number, 13, and leaves take 12 as it was
    size12 = os.path.getsize(os.path.join(takes, "scene7_T012.fptake"))
    command("/fp/slate", "scene7")
    command("/fp/take", 12, expect="error: take 12 of slate scene7 exists (")
    want(command("/fp/record/start"), recording=1, slate="scene7", take=13)
    time.sleep(0.2)
    want(command("/fp/record/stop"), recording=0, take=13)
    if os.path.getsize(os.path.join(takes, "scene7_T012.fptake")) != size12:
        fail("take 12 changed after /fp/take 12")
    command("/fp/play", expect="error: no transport")
    command("/fp/radius", 2.5)
    # a radius the face cannot use (a millionth to 10 times its diagonal): an error, the radius
    # stays (1e-30 was taken, and the engine then refused every frame, the face still)
    command("/fp/radius", 1e-30, expect="error: radius 1e-30 outside [")
    command("/fp/radius", 1e6 - 1, expect="error: radius 999999 outside [")
    # every finite radius reaches the range check and is answered (0, negative, 1e6 and
    # beyond were refused unanswered as bad values); NaN and inf stay refused (bad value)
    for r, words in [(0.0, "0"), (-1.0, "-1"), (1e6, "1e+06"), (("d", 1e300), "1e+300"),
                     (("i", -5), "-5"), (("d", 1e-7), "1e-07")]:
        command("/fp/radius", r, expect="error: radius %s outside [" % words)
    command("/fp/radius", 2.5)
    command("/fp/channel", "jaw.open", 0.2)
    command("/fp/channel", "no.such.channel", 0.2, expect="error")
    command("/fp/cancel")
    # Live Link Face's recording commands
    want(command("/Slate", "llf"), slate="llf", recording=0)
    want(command("/Take", 2), take=2)
    st = command("/RecordStart", "llf", 3)
    want(st, recording=1, slate="llf", take=3)
    time.sleep(0.3)
    want(command("/RecordStop"), recording=0, take=3, slate="llf")
    st = command("/RecordStart")          # LLF without arguments: the slate kept, the next number
    want(st, recording=1, slate="llf", take=4)
    time.sleep(0.2)
    want(command("/RecordStop"), recording=0, take=4)
    # a button for recording: pressed (1.0) starts a take with the slate and next number,
    # let go (0.0) does nothing; a second button stops it
    sock.sendto(fposc.encode("/fp/record/start", 0.0), target)
    if receive(0.5) is not None:
        fail("a button let go (/fp/record/start 0.0) was answered")
    want(command("/fp/record/start", 1.0), recording=1, slate="llf", take=5)
    time.sleep(0.2)
    want(command("/fp/record/stop", 1), recording=0, take=5)
    time.sleep(1.2)                       # (a push a second at least)
    if not any(p["recording"] == 1 for p in pushes) or not pushes:
        fail("the subscriber got no push while recording (%d pushes)" % len(pushes))
    print("  %d pushes to the subscriber; %d replies" % (len(pushes), replies))

    # 5. hostile packets
    before = command("/fp/status")
    files_before = sorted(os.listdir(takes))
    rng = random.Random(55)
    pkts, expected = [], 0
    valid = ["/fp/record/start", "/fp/engage", "/fp/radius", "/fp/mapping", "/fp/channel",
             "/fp/seek", "/fp/take", "/RecordStart", "/Slate", "/Take", "/fp/subscribe", "/fp/quit"]
    kinds = 12
    for k in range(10000):
        kind = k % kinds
        if kind == 0:                     # random bytes
            p = bytes(rng.getrandbits(8) for _ in range(rng.randint(1, 200)))
            if p[:1] == b"/" or p[:8] == b"#bundle\0":
                p = b"\x00" + p[1:]
        elif kind == 1:                   # a valid message cut short
            m = fposc.encode("/fp/record/start", "s1", 5)
            cut = rng.randrange(5, len(m))
            p = m[:cut if cut % 4 else cut - 1]          # (not a multiple of 4: never OSC)
        elif kind == 2:                   # wrong types
            p = fposc.encode(rng.choice(["/fp/radius", "/fp/seek", "/Take"]), "text")
        elif kind == 3:                   # NaN, inf radius (a finite one is answered)
            p = fposc.encode("/fp/radius", rng.choice([float("nan"), float("inf"), float("-inf"),
                                                       ("d", float("nan"))]))
        elif kind == 4:                   # slates with paths or too long
            p = fposc.encode(rng.choice(["/fp/record/start", "/RecordStart", "/Slate"]),
                             rng.choice(["../../etc/x", "a/b", ".hidden", "", "x" * 300, "sp ace"]))
        elif kind == 5:                   # a mapping by path, with ':'
            p = fposc.encode("/fp/mapping", rng.choice(["/tmp/evil.so", "../x", "map:arg", "", "a b"]))
        elif kind == 6:                   # take numbers out of range
            p = fposc.encode(rng.choice(["/Take", "/fp/take"]), rng.choice([0, -5, 10 ** 7]))
        elif kind == 7:                   # unknown addresses
            p = fposc.encode("/fp/" + "".join(rng.choice("abcxyz/") for _ in range(8)), 1)
        elif kind == 8:                   # bundles nested 9 deep
            p = fposc.encode("/fp/engage")
            for _ in range(9):
                p = fposc.bundle(p)
        elif kind == 9:                   # a bundle whose element size lies
            p = b"#bundle\0" + struct.pack(">Q", 1) + struct.pack(">i", 4000) + fposc.encode("/fp/engage")
        elif kind == 10:                  # extra arguments (one number is a button's value)
            p = fposc.encode(rng.choice(["/fp/engage", "/fp/record/stop", "/RecordStop", "/fp/quit"]),
                             *rng.choice([(1, 2), ("x",), (0.0, 1.0), (float("nan"),)]))
        else:                             # channel with a bad name or value
            p = fposc.encode("/fp/channel", rng.choice(["jaw open", "", "j" * 80, "jaw.open"]),
                             rng.choice([float("nan"), "x"]))
        pkts.append(p)
        expected += 1
    # in batches of 100, each followed by a status round trip (the network thread reads in
    # order, so the batch was read when the reply comes): no batch outgrows the socket's
    # buffer on a loaded machine, and every hostile packet is read
    sent = 0
    for i in range(0, len(pkts), 100):
        for p in pkts[i:i + 100]:
            sock.sendto(p, target)
            sent += 1
        sock.sendto(fposc.encode("/fp/status"), target)
        st = receive(10)
        if st is None or st["command"] != "/fp/status":
            fail("after %d hostile packets: %r instead of the status" % (sent, st))
    got_reply = receive(0.5)
    if got_reply is not None:
        fail("a hostile packet was answered: %r" % got_reply)
    after = command("/fp/status")
    delta = after["refused"] - before["refused"]
    print("  %d hostile packets sent; refused count %d -> %d (+%d)" % (sent, before["refused"], after["refused"], delta))
    if delta != expected:
        fail("refused grew by %d, wanted %d (one per hostile message)" % (delta, expected))
    for k in ("state", "slate", "take", "recording"):
        if before[k] != after[k]:
            fail("the hostile packets changed %s: %r -> %r" % (k, before[k], after[k]))
    if sorted(os.listdir(takes)) != files_before:
        fail("the hostile packets changed the takes folder")
    if run.poll() is not None:
        fail("the run ended during the hostile packets (%s)" % run.returncode)
    command("/fp/quit")
    try:
        rc = run.wait(60)
    except subprocess.TimeoutExpired:
        run.kill()
        fail("the run did not end after /fp/quit")
    out = open(os.path.join(work, "run.out")).read()
    err = open(os.path.join(work, "run.err")).read()
    print(out.strip())
    print("\n".join(l for l in err.splitlines() if "--control" in l or " take " in l))
    if rc != 0:
        fail("run exited %d" % rc)
    if "engaged 1, committed 1" not in out:
        fail("the run's summary does not say 'engaged 1, committed 1'")
    print("replies %d (every command answered)" % replies)
    print("PASS")
finally:
    if run.poll() is None:
        run.kill()
