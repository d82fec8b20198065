# hil-timeout: 60
# SocketCAN needs no I/O thread: its socket is opened SOCK_NONBLOCK, so a send on a full
# transmit queue fails at once (EAGAIN/ENOBUFS, reported as a transmit failure) instead of
# waiting. Here the queue really is full: a token-bucket qdisc lets 1 kbit/s through and holds
# the rest (netem would not do: it detaches frames from their socket), so the
# socket's send buffer fills within a fraction of a second (a blocking socket would then sleep
# in write). hil-loop-io-check runs the loop's device work (poll, send of a 3-frame classic CAN
# command) at 1 kHz for 2 s beside cyclictest and must find: the socket O_NONBLOCK; on the loop
# thread no allocation, no lock call, no system call but its clock and the socket's read and
# write; sends failing; no tick longer than cyclictest's longest latency + 2 periods, the median
# tick within one period.
set -eu
. "$HIL_GUEST/lib.sh"
vcan_up vcan0 16
tc qdisc add dev vcan0 root tbf rate 1kbit burst 1600 limit 10000000 || fail "tc qdisc add dev vcan0 root tbf"
tc qdisc show dev vcan0
rc=0
"$HIL_BUILD/hil/bin/hil-loop-io-check" --transport socketcan --address vcan0 --framing can --node 4 --seconds 2 \
    --cyclictest --allow-syscalls read,write --expect-send-errors || rc=$?
tc -s qdisc show dev vcan0
[ $rc -eq 0 ] || fail "a send on SocketCAN's full transmit queue held up the loop (see above)"
pass "SocketCAN on a full transmit queue: O_NONBLOCK socket, sends fail at once, ticks bounded by cyclictest"
