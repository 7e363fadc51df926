// Tar member names as Keel reads them: the server's bundle check before a mission is stored,
// and the worker's unpacker before it writes a file. Both split a name the same way and refuse
// the same names (absolute, or with a ".." component), each in the words of its own errors.
#pragma once

#include <string>
#include <vector>

namespace keel {

// "./a//b/" -> {"a", "b"}: split at '/', empty and "." components dropped.
std::vector<std::string> tar_path_components(const std::string& name);
// The first `count` components joined with '/' (all by default).
std::string join_tar_path(const std::vector<std::string>& parts, size_t count = size_t(-1));
// True for a ".." component: the name could leave the folder it is unpacked into.
bool has_parent_component(const std::vector<std::string>& parts);

}  // namespace keel
