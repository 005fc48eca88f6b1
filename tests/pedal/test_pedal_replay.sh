#!/usr/bin/env bash
# The pedal plugin under docs/devices.md's own replay recipe, as an outside check runs it:
# `umockdev-run --device pedal.umockdev --ioctl /dev/bus/usb/001/005=pedal.ioctl -- prog`,
# the script's USBDEVFS_REAPURBNDELAY lines completing the reader's interrupt URBs. umockdev
# answers only what the script and its own state machine know (no DISCONNECT_CLAIM, no
# USBDEVFS_IOCTL) and completes a URB only where the submitted buffer length equals the
# line's buflen, so:
#  1. a VEC Infinity (05f3:00ff) with buflen = wMaxPacketSize (8), then 2 (the report's size)
#     and 64: `facepuppet monitor pedal --count 5` prints connected, left down, left up,
#     right down, right up, and exits 0;
#  2. a PCsensor FootSwitch (0c45:7403, boot keyboard interface, 9-byte reports with id 1):
#     keys a, b, c give left, middle, right;
#  3. the same pedal with `pedal,keys=c,b,a` (the commas docs/pedal.md allows): c, b, a give
#     left, middle, right.
# Run from the repository root by ctest (FP_BUILD_DIR). SPDX-License-Identifier: GPL-3.0-or-later
set -u
build=${FP_BUILD_DIR:-build}
fp=$build/bin/facepuppet
tmp=$(mktemp -d "${TMPDIR:-/tmp}/fp-pedal-replay-XXXXXX")
trap 'rm -rf "$tmp"' EXIT
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }
command -v umockdev-run >/dev/null || { echo "umockdev-run missing (Debian umockdev)"; exit 1; }

# device NAME DEVNUM VID PID PRODUCT DESCRIPTORS: a .umockdev description of a USB device
device() {
    cat <<EOD
P: /devices/pci0000:00/usb1/$1
N: bus/usb/001/$2
E: SUBSYSTEM=usb
E: DEVTYPE=usb_device
E: DRIVER=usb
E: BUSNUM=001
E: DEVNUM=$2
E: DEVNAME=/dev/bus/usb/001/$2
E: PRODUCT=$5
A: busnum=1\n
A: devnum=$((10#$2))\n
A: bConfigurationValue=1\n
A: speed=12\n
A: idVendor=$3\n
A: idProduct=$4\n
H: descriptors=$6
EOD
}
# the same descriptors as tests/pedal/pedal_emu.c's
device 1-1 005 05f3 00ff 5f3/ff/100 \
    "12010002000000""08""f305""ff00""0001""010200""01""09022200""01""01""00""80""32""0904""00""00""01""03""00""00""00""092110010001""22""3f00""0705""81""03""0800""0a" \
    >"$tmp/vec.umockdev"
device 1-2 004 0c45 7403 c45/7403/100 \
    "12011001000000""08""450c""0374""0001""010200""01""09023b00""02""01""00""80""32""0904""00""00""01""03""00""00""00""092110010001""22""2200""0705""82""03""0800""0a""0904""01""00""01""03""01""01""00""092110010001""22""4500""0705""81""03""1000""0a" \
    >"$tmp/kbd.umockdev"

# run DEVICE NODE SCRIPT COUNT: monitor's JSON lines (the script loops at its end: --count)
run() {
    timeout -k 2 20 umockdev-run --device "$1" --ioctl "$2=$3" -- "$fp" monitor pedal --count "$4" \
        2>"$tmp/err"
}
# the button events of monitor's lines as "left+ left- ..."
buttons() { sed -n 's/.*"type":"button","button":"\([a-z]*\)","down":\(true\|false\).*/\1\2/p' |
                sed 's/true$/+/; s/false$/-/' | tr '\n' ' '; }

# ---- 1. VEC: buflen 8 (wMaxPacketSize), 2, 64 -------------------------------------------
for buflen in 8 2 64; do
    {
        echo "@DEV /dev/bus/usb/001/005 (usbdevfs)"
        for r in 0100 0000 0400 0000; do
            echo "USBDEVFS_REAPURBNDELAY 0 1 129 0 0 $buflen 2 0 $r"
        done
    } >"$tmp/vec$buflen.ioctl"
    out=$(run "$tmp/vec.umockdev" /dev/bus/usb/001/005 "$tmp/vec$buflen.ioctl" 5)
    rc=$?
    [[ $rc == 0 ]] || fail "VEC, buflen $buflen: monitor exit $rc: $(cat "$tmp/err")"
    grep -q '"code":"connected".*05f3:00ff' <<<"$out" || fail "VEC, buflen $buflen: not connected: $(cat "$tmp/err")"
    got=$(buttons <<<"$out")
    [[ $got == "left+ left- right+ right- " ]] || fail "VEC, buflen $buflen: buttons '$got', expected 'left+ left- right+ right- '"
done

# ---- 2. PCsensor: keys a, b, c on the boot keyboard interface (EP 0x81, 16-byte packets) --
{
    echo "@DEV /dev/bus/usb/001/004 (usbdevfs)"
    for k in 04 00 05 00 06 00; do
        echo "USBDEVFS_REAPURBNDELAY 0 1 129 0 0 16 9 0 010000${k}0000000000"
    done
} >"$tmp/kbd.ioctl"
out=$(run "$tmp/kbd.umockdev" /dev/bus/usb/001/004 "$tmp/kbd.ioctl" 7)
rc=$?
[[ $rc == 0 ]] || fail "PCsensor: monitor exit $rc: $(cat "$tmp/err")"
got=$(buttons <<<"$out")
[[ $got == "left+ left- middle+ middle- right+ right- " ]] ||
    fail "PCsensor: buttons '$got', expected 'left+ left- middle+ middle- right+ right- ': $(cat "$tmp/err")"

# ---- 3. keys= with commas, as docs/pedal.md gives them (before: "'b' is not key=value") ----
out=$(timeout -k 2 20 umockdev-run --device "$tmp/kbd.umockdev" --ioctl /dev/bus/usb/001/004="$tmp/kbd.ioctl" \
    -- "$fp" monitor pedal,keys=c,b,a --count 7 2>"$tmp/err")
rc=$?
[[ $rc == 0 ]] || fail "PCsensor keys=c,b,a: monitor exit $rc: $(cat "$tmp/err")"
got=$(buttons <<<"$out")
[[ $got == "right+ right- middle+ middle- left+ left- " ]] ||
    fail "PCsensor keys=c,b,a: buttons '$got', expected 'right+ right- middle+ middle- left+ left- '"

if (( fails )); then echo "$fails failure(s)"; exit 1; fi
echo "ok: VEC at buflen 8, 2, 64, PCsensor a/b/c and keys=c,b,a read through umockdev-run's replay"
