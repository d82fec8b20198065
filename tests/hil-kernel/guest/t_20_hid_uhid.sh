# hil-timeout: 60
# uhid -> /dev/hidrawN -> hidapi (hidraw backend) on the real kernel: enumeration by VID:PID,
# input/output/feature reports, node removal on destroy (see probes/uhid_hidapi_probe.c).
set -eu
. "$HIL_GUEST/lib.sh"
exec "$HIL_BUILD/hil/bin/hil-uhid-probe" 1209 0001
