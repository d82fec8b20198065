// Who may own a channel segment, and where a writer goes when another user holds its name.
//
// POSIX shm names live in one directory (/dev/shm, sticky, world-writable): any local user can
// create "/hapfluid.sim_samples" first. So:
//   * A segment is trusted only if it is a regular file owned by this process's effective user
//     (the rig's services run as one user) or by root, and nobody but its owner may write it
//     (no group or other write bit). Readers refuse anything else and name its owner.
//   * A writer that finds its name held by an untrusted user neither uses nor removes it: it
//     creates "<name>.<16 hex digits>" instead, and readers that find no trusted segment under
//     the name look for those. The squatter blocks nothing and receives nothing.
#pragma once

#include <sys/stat.h>

#include <string>
#include <vector>

namespace hapfluid::shm::detail {

// This process's effective user or root.
bool trusted_owner(uid_t uid);
// Empty if `st` describes a segment this process may trust, else why not (naming the owner).
std::string trust_problem(const struct stat& st);
// "uid 65534 (nobody)".
std::string describe_user(uid_t uid);
// Existing fallback names of `name` ("/<x>" -> "/<x>.<hex>"), in no particular order.
std::vector<std::string> fallback_names(const std::string& name);
// A new, unpredictable fallback name for `name`.
std::string new_fallback_name(const std::string& name);

}  // namespace hapfluid::shm::detail
