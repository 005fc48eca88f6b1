# Sourced by the link tests: a `facepuppet run` listening for OSC on a free port.
# listen_run NAME LIMIT_S ARGS...: `facepuppet run ARGS -o $tmp/NAME.obj -q` in the background
# (at most LIMIT_S seconds), each @PORT@ in ARGS a random high UDP port, another one when that
# is taken ("cannot listen", 5 tries); returns once it listens, with $port and $run_pid set and
# its output in $tmp/NAME.out and $tmp/NAME.err. Needs fp, pd (the plugin dir option), tmp
# and fail. SPDX-License-Identifier: GPL-3.0-or-later
listen_run() {
    local name=$1 limit=$2 attempt i
    shift 2
    for attempt in 1 2 3 4 5; do
        port=$((20000 + RANDOM % 40000))
        timeout "$limit" "$fp" run "${pd[@]}" "${@//@PORT@/$port}" -o "$tmp/$name.obj" -q \
            >"$tmp/$name.out" 2>"$tmp/$name.err" &
        run_pid=$!
        for i in $(seq 600); do # (the face loads first: up to 60 s)
            grep -q "listening on" "$tmp/$name.err" && return 0
            kill -0 $run_pid 2>/dev/null || break
            sleep 0.1
        done
        grep -q "listening on" "$tmp/$name.err" && return 0
        wait $run_pid
        grep -q "cannot listen" "$tmp/$name.err" && continue
        cat "$tmp/$name.err"
        fail "$name did not listen"
    done
    fail "no free port for $name in 5 tries"
}
