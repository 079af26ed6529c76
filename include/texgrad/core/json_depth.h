// Bounding untrusted JSON before a recursive parser sees it (glTF files, viewer messages).
#pragma once

#include <string_view>

namespace texgrad {

/// True if the JSON text nests arrays and objects more than maxDepth levels deep; a scan without
/// recursion in which brackets inside strings do not count.
bool jsonNestsDeeperThan(std::string_view text, int maxDepth);

}  // namespace texgrad
