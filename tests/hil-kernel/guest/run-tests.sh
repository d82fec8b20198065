#!/bin/bash
# Runs the planned guest tests inside the HIL guest (chrooted into the host root), each in its
# own scratch folder with its own time limit, and writes junit.xml and summary.txt to the results
# share after every test, so a guest that hangs later still leaves what finished.
#   plan.tsv lines: NAME <tab> TIMEOUT_S <tab> SCRIPT
set -u
res="$HIL_RESULTS"
mkdir -p "$res/logs"
export HIL_BIN="$HIL_BUILD/bin"
export HIL_PY="$HIL_SRC/.venv/bin/python"
export HIL_GUEST="$HIL_SRC/tests/hil-kernel/guest"

names=() statuses=() durations=() messages=()

# Whatever a test set up in the kernel goes away after it, passed or not, so the next test starts
# from a clean guest: USB gadgets (unbound, FunctionFS unmounted, configfs tree removed), vcan
# interfaces and uhid devices (those die with their processes, killed before this runs).
teardown() {
    local g l d
    for g in /sys/kernel/config/usb_gadget/*/; do
        [ -d "$g" ] || continue
        echo "" >"$g/UDC" 2>/dev/null
        for l in "$g"configs/*/*; do [ -L "$l" ] && rm -f "$l"; done
    done
    awk '$3 == "functionfs" { print $2 }' /proc/mounts | while read -r d; do umount "$d" 2>/dev/null; done
    for g in /sys/kernel/config/usb_gadget/*/; do
        [ -d "$g" ] || continue
        rmdir "$g"configs/*/strings/* "$g"configs/* "$g"functions/* "$g"strings/* "$g" 2>/dev/null
    done
    for d in $(ip -o link show type vcan 2>/dev/null | awk -F': ' '{ print $2 }'); do ip link del "$d"; done
}

xml_escape() { sed -e 's/&/\&amp;/g' -e 's/</\&lt;/g' -e 's/>/\&gt;/g' -e 's/"/\&quot;/g'; }

write_reports() {
    local n=${#names[@]} failed=0 i
    for ((i = 0; i < n; i++)); do [ "${statuses[$i]}" = pass ] || failed=$((failed + 1)); done
    {
        echo '<?xml version="1.0" encoding="UTF-8"?>'
        echo "<testsuite name=\"hil-kernel\" tests=\"$n\" failures=\"$failed\" errors=\"0\" hostname=\"qemu-$(uname -r)\">"
        for ((i = 0; i < n; i++)); do
            echo "  <testcase classname=\"hil-kernel\" name=\"${names[$i]}\" time=\"${durations[$i]}\">"
            if [ "${statuses[$i]}" != pass ]; then
                echo "    <failure message=\"$(printf '%s' "${messages[$i]}" | xml_escape)\" type=\"${statuses[$i]}\"/>"
            fi
            echo "    <system-out>"
            tail -n 200 "$res/logs/${names[$i]}.log" 2>/dev/null | tr -cd '\11\12\15\40-\176' | xml_escape
            echo "    </system-out>"
            echo "  </testcase>"
        done
        echo "</testsuite>"
    } >"$res/junit.xml.tmp" && mv "$res/junit.xml.tmp" "$res/junit.xml"
    summary="HIL-SUMMARY tests=$n passed=$((n - failed)) failed=$failed kernel=$(uname -r) realtime=$(cat /sys/kernel/realtime 2>/dev/null || echo 0)"
}

total=$(wc -l <"$res/plan.tsv")
idx=0
while IFS=$'\t' read -r name limit script; do
    idx=$((idx + 1))
    echo "HIL-TEST [$idx/$total] $name: running (limit ${limit} s)" >/dev/console
    work="/tmp/hil/$name"
    mkdir -p "$work"
    t0=$(date +%s.%N)
    # timeout(1) puts the test in its own process group (pgid = its pid): killed as a whole
    # afterwards, so a fake device a test left running cannot disturb the next test.
    (cd "$work" && HIL_WORK="$work" HIL_TEST="$name" exec timeout -k 5 "$limit" bash "$script") \
        >"$res/logs/$name.log" 2>&1 </dev/null &
    pid=$!
    wait $pid
    rc=$?
    kill -KILL -- -$pid 2>/dev/null
    sleep 0.2  # let the killed processes release their files before the teardown
    teardown
    t1=$(date +%s.%N)
    dur=$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.1f", b - a }')
    if [ $rc -eq 0 ]; then
        st=pass msg=""
    elif [ $rc -eq 124 ] || [ $rc -eq 137 ]; then
        st=timeout msg="exceeded its ${limit} s limit"
    else
        st=fail msg="exit status $rc: $(grep -m1 -E '^(FAIL|ERROR)' "$res/logs/$name.log" || tail -n1 "$res/logs/$name.log")"
    fi
    names+=("$name") statuses+=("$st") durations+=("$dur") messages+=("$msg")
    write_reports
    echo "HIL-TEST [$idx/$total] $name: ${st^^} (${dur} s guest time)${msg:+ - $msg}" >/dev/console
    grep -h '^KNOWN-BUG' "$res/logs/$name.log" | sort -u | sed "s/^/HIL-KNOWN-BUG $name: /" >/dev/console
done <"$res/plan.tsv"

write_reports
echo "$summary" >"$res/summary.txt"
echo "$summary" >/dev/console
sync
