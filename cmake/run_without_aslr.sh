#!/bin/sh
# Runs a ThreadSanitizer test with address-space randomisation off for its process (see
# hapfluid_add_tsan_gtest in hapfluid.cmake). Where the kernel or a seccomp profile refuses the
# personality change (some containers), the test runs as it is: on the usual 28-bit mmap
# randomisation TSan needs nothing, and on a wider one it stops with its own clear message.
if setarch "$(uname -m)" -R true 2>/dev/null; then
  exec setarch "$(uname -m)" -R "$@"
fi
exec "$@"
