# hil-timeout: 40
# SocketCAN on the real kernel with the standard tools: a classic-only bus (vcan0, MTU 16, like
# a 1 Mbit/s classic CAN rig) and a CAN FD bus (vcanfd0, MTU 72). Frames sent with cansend must
# reach candump bit-exact (IDs, DLC, data, FD flags); an FD frame must be refused on the classic
# bus, because a driver that "sends" FD frames onto a classic bus would lose the device's state.
set -eu
. "$HIL_GUEST/lib.sh"
vcan_up vcan0 16
vcan_up vcanfd0 72
ip -details link show vcan0
ip -details link show vcanfd0

sent_classic="123#DEADBEEF 12345678#0011223344556677 7FF#R 000#"
payload64=$(printf '%02X' $(seq 0 63))
sent_fd="123##1000102030405060708090A0B0C0D0E0F 1ABCDEF0##3$payload64"
# The kernel marks every frame that travelled as CAN FD with CANFD_FDF (0x04) in the flags
# nibble, so BRS (1) comes back as 5 and BRS|ESI (3) as 7.
want_fd="123##5000102030405060708090A0B0C0D0E0F 1ABCDEF0##7$payload64"

candump -L -n 4 vcan0 >classic.log &
dump1=$!
candump -L -n 2 vcanfd0 >fd.log &
dump2=$!
wait_for 20 can_listening vcan0 || fail "candump never bound to vcan0"
wait_for 20 can_listening vcanfd0 || fail "candump never bound to vcanfd0"
for f in $sent_classic; do cansend vcan0 "$f" || fail "cansend vcan0 $f"; done
for f in $sent_fd; do cansend vcanfd0 "$f" || fail "cansend vcanfd0 $f"; done
if cansend vcan0 "123##1DEADBEEF" >fd_on_classic.err 2>&1; then
    fail "an FD frame was accepted on the classic-only bus vcan0 (MTU 16)"
fi
echo "FD frame on vcan0 refused: $(cat fd_on_classic.err)"
wait "$dump1" || fail "candump vcan0 did not get 4 frames"
wait "$dump2" || fail "candump vcanfd0 did not get 2 frames"
cat classic.log fd.log
got_classic=$(awk '{print $3}' classic.log | tr '\n' ' ' | sed 's/ $//')
got_fd=$(awk '{print $3}' fd.log | tr '\n' ' ' | sed 's/ $//')
[ "$got_classic" = "$sent_classic" ] || fail "classic: sent [$sent_classic] got [$got_classic]"
[ "$got_fd" = "$want_fd" ] || fail "FD: sent [$sent_fd] expected [$want_fd] got [$got_fd]"
pass "4 classic frames (std/ext/RTR/empty) on vcan0 and 2 FD frames (16 and 64 bytes, BRS) on vcanfd0 round-tripped cansend -> candump"
