# hil-timeout: 90
# python-can's socketcan interface on the real kernel (see can_python_probe.py for what and why).
set -eu
. "$HIL_GUEST/lib.sh"
vcan_up vcan0 16
vcan_up vcanfd0 72
exec "$HIL_PY" "$HIL_GUEST/can_python_probe.py"
