// A process maps a channel object that another process can shrink (ftruncate) at any time; a load
// or store on a page beyond the new end raises SIGBUS, which would kill haptic-rt. A guarded
// mapping turns that into a flag: the SIGBUS handler maps zero pages over the whole mapping,
// marks it truncated and lets the access run again. The channel code then sees an intact-looking
// but empty slot and, through mapping_truncated(), reports the segment as corrupt.
#pragma once

#include <cstddef>

namespace hapfluid::shm::detail {

// Non-RT (installs the handler once). Returns a guard id, or -1 when every guard is in use.
int guard_mapping(const std::byte* base, std::size_t bytes, int prot);
// Call before unmapping: the address range may be reused by an unrelated mapping.
void unguard_mapping(int guard);
// Wait-free, no syscall. False for guard -1 (an anonymous mapping nobody else can shrink).
bool mapping_truncated(int guard);

}  // namespace hapfluid::shm::detail
