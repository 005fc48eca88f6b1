#!/usr/bin/env python3
"""A CyberGlove box on a pty whose bytes take the time the reader's line speed gives them
(10 bits a byte, 8N1, the speed read with tcgetattr on the master: what the reader set on the
slave), written from shared/docs/devices.md alone: ?G ?S ?N ?R ?V ?D ?U answered `?` X value
0x00, `X value` commands X 0x00, `t w1 w2\\r` t 0x00, S streams 22-sensor records with the
5-byte timestamp on (?D = 1) and the status byte once `U 1` (30 bytes: 250 ms at 1200 baud),
0x03 or ^c stop. Usage: paced_box.py LINK SECONDS (the link to the slave; exits after SECONDS).
SPDX-License-Identifier: GPL-3.0-or-later"""
import os, pty, select, sys, termios, time, tty

link, seconds = sys.argv[1], float(sys.argv[2])
master, slave = pty.openpty()
tty.setraw(slave)
name = os.ttyname(slave)
os.close(slave)
if os.path.lexists(link):
    os.unlink(link)
os.symlink(name, link)
SPEEDS = {getattr(termios, 'B%d' % b): b for b in (1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200)}
state = {'D': 1, 'U': 0, 'streaming': False, 'period': 0.01}
t0 = time.monotonic()

def send(data):
    """write data at the line's pace: each byte 10 bits at the speed the reader set"""
    for b in data:
        baud = SPEEDS.get(termios.tcgetattr(master)[5], 115200)
        os.write(master, bytes([b]))
        time.sleep(10.0 / baud)

def record():
    ms = int((time.monotonic() - t0) * 1000)
    rec = b'S' + bytes(100 + (i * 7 + ms // 50) % 100 for i in range(22))
    if state['D']:
        rec += bytes(1 + (ms >> (7 * k) & 0x7f) for k in range(5))
    if state['U']:
        rec += b'\x01'  # glove plugged
    return rec + b'\0'

buf = bytearray()
next_rec = 0.0
end = t0 + seconds
while time.monotonic() < end:
    r, _, _ = select.select([master], [], [], 0.002)
    if r:
        try:
            buf += os.read(master, 256)
        except OSError:
            pass
    while buf:
        c = buf[0]
        if c == 0x03:
            del buf[0]; state['streaming'] = False
        elif c == ord('^'):
            if len(buf) < 2: break
            del buf[:2]; state['streaming'] = False
        elif c == ord('?'):
            if len(buf) < 2: break
            x = chr(buf[1]); del buf[:2]
            v = {'G': b'\x03', 'S': b'\x16', 'N': b'\x16', 'R': b'\x01', 'V': b'paced 1',
                 'D': bytes([state['D']]), 'U': bytes([state['U']])}.get(x)
            send(b'?' + x.encode() + v + b'\0' if v is not None else b'e?\0')
        elif c == ord('S'):
            del buf[0]; state['streaming'] = True
        elif c == ord('t'):
            i = buf.find(b'\r')
            if i < 0: break
            del buf[:i + 1]; send(b't\0')
        elif chr(c) in 'NDUFLJWQB':
            if len(buf) < 2: break
            state[chr(c)] = buf[1]; del buf[:2]; send(bytes([c]) + b'\0')
        else:
            del buf[0]; send(b'e?\0')
    if state['streaming'] and time.monotonic() >= next_rec:
        send(record())
        next_rec = time.monotonic() + state['period']
os.unlink(link)
