// Nesting depth of JSON text, found without recursion (include/texgrad/core/json_depth.h).
#include "texgrad/core/json_depth.h"

namespace texgrad {

bool jsonNestsDeeperThan(std::string_view text, int maxDepth) {
  // Brackets inside strings do not nest; a string ends at a quote that no backslash escapes.
  // Unbalanced closers can only lower the count: a parser stops at the first one anyway.
  int depth = 0;
  bool inString = false, escaped = false;
  for (const char c : text) {
    if (inString) {
      if (escaped)
        escaped = false;
      else if (c == '\\')
        escaped = true;
      else if (c == '"')
        inString = false;
    } else if (c == '"') {
      inString = true;
    } else if (c == '[' || c == '{') {
      if (++depth > maxDepth) return true;
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return false;
}

}  // namespace texgrad
