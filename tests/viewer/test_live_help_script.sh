#!/bin/sh
# live --help names every command its --script takes: the parser's own list (the error for
# a command it does not know: "is not one of: wait hands|end|reload|frames N|seconds S, key
# NAME, ...") against the help's text. Before, 'wait reload' and 'print mapping' were in the
# parser alone. No display needed (the script is refused before the window, exit 64).
# Usage: test_live_help_script.sh FACEPUPPET
set -u
fp=$1
err=$("$fp" live --script "bogus" 2>&1 >/dev/null)
rc=$?
[ $rc -eq 64 ] || { echo "$err"; echo "FAIL: live --script bogus exited $rc, not 64"; exit 1; }
list=${err#*is not one of: }
help=$("$fp" live --help 2>&1)
fail=0
# each alternative: "wait hands|end|reload|frames N" -> wait hands, wait end, wait reload, ...
for item in $(printf '%s\n' "$list" | tr ',' '\n' | sed 's/^ *//' | awk '{
        n = split($0, w, " "); verb = w[1]; rest = substr($0, length(verb) + 2)
        m = split(rest, alt, "|")
        if (m == 0 || rest == "") { print verb; next }
        for (i = 1; i <= m; i++) { split(alt[i], a, " "); print verb "_" a[1] } }'); do
    verb=${item%%_*} word=${item#*_}
    [ "$word" = "$item" ] && word=""
    case "$word" in ""|[A-Z]*) want="$verb" ;; *) want="$verb $word" ;; esac
    if ! printf '%s\n' "$help" | tr '\n' ' ' | grep -q -- "$want"; then
        # 'wait hands|end|frames N' in the help counts for each alternative
        if [ -n "$word" ] && printf '%s\n' "$help" | grep -q -- "$verb [a-zA-Z |]*|$word"; then continue; fi
        echo "FAIL: live --help does not name the script command '$want'"
        fail=1
    fi
done
[ $fail -eq 0 ] && echo PASS
exit $fail
