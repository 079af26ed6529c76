// scanObjLines: the checks tinyobjloader does not make, with the file's line numbers.
#include "obj_lines.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include "texgrad/core/error.h"
#include "texgrad/core/path_exists.h"

namespace texgrad::obj {
namespace {

/// Where a line is, as messages name it.
std::string at(const std::filesystem::path& path, size_t line) {
  return path.string() + " line " + std::to_string(line) + ": ";
}

/// True if `token` is exactly one number of type T.
template <typename T>
bool parse(std::string_view token, T& value) {
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  return ec == std::errc() && end == token.data() + token.size();
}

/// A 'v' or 'vt' line: every coordinate must be a finite number (tinyobjloader reads "nan",
/// "inf" and other non-numbers as 0).
void checkCoordinates(std::istringstream& words, bool isVertex, size_t index,
                      const std::string& where) {
  const std::string what = (isVertex ? "vertex " : "texture coordinate ") + std::to_string(index);
  std::string token;
  for (int c = 0; c < (isVertex ? 3 : 2) && words >> token; ++c) {
    double value = 0.0;
    const bool number = parse(token, value);
    if (!number || !std::isfinite(value))
      throw InvalidInputError(where + what + " has coordinate '" + token + "'" +
                              (number ? ", which is not finite" : ", which is not a number") +
                              "; fix or remove it in the mesh file");
  }
}

/// Largest 1-based index an 'f' line names, and the line that names it (checked at the end,
/// since the counts of 'v' and 'vt' lines are known only then).
struct MaxIndex {
  long value = 0;
  size_t line = 0;
};

/// Checks one corner 'v[/vt][/vn]' of an 'f' line; negative (relative) indices must reach a
/// line already read.
void checkCorner(const std::string& token, const std::array<size_t, 2>& counts,
                 std::array<MaxIndex, 2>& max, size_t line, const std::string& where) {
  const auto fail = [&](const std::string& why) {
    throw InvalidInputError(where + "face corner '" + token + "' " + why +
                            "; fix the 'f' line or re-export the mesh");
  };
  size_t start = 0;
  for (int field = 0; field < 3 && start <= token.size(); ++field) {
    const size_t slash = std::min(token.find('/', start), token.size());
    const std::string_view text = std::string_view(token).substr(start, slash - start);
    start = slash + 1;
    if (text.empty() && field > 0) continue;  // 'v//vn' or a trailing '/'
    long index = 0;
    if (!parse(text, index) || index == 0) fail("is not 'v/vt' with non-zero integer indices");
    if (field == 2) continue;  // normals are not used
    const auto which = static_cast<size_t>(field);
    const char* kind = field == 0 ? "vertex" : "texture coordinate";
    if (index < -static_cast<long>(counts[which]))  // not -index: LONG_MIN has no negation
      fail("refers to " + std::string(kind) + " " + std::to_string(index) + " but only " +
           std::to_string(counts[which]) + " precede it");
    if (index > max[which].value) max[which] = {index, line};
  }
  if (start <= token.size()) fail("has more than three '/'-separated fields");
}

}  // namespace

ObjLines scanObjLines(const std::filesystem::path& path) {
  std::ifstream in(path);
  ObjLines result;
  std::array<size_t, 2> counts{0, 0};  // 'v' and 'vt' lines so far
  std::array<MaxIndex, 2> max{};
  const std::filesystem::path folder = std::filesystem::absolute(path).parent_path();
  std::string text;
  for (size_t line = 1; std::getline(in, text); ++line) {
    std::istringstream words(text.substr(0, text.find('#')));
    std::string keyword;
    words >> keyword;
    const std::string where = at(path, line);
    if (keyword == "v" || keyword == "vt") {
      const bool isVertex = keyword == "v";
      checkCoordinates(words, isVertex, counts[isVertex ? 0 : 1]++, where);
    } else if (keyword == "f") {
      int corners = 0;
      for (std::string token; words >> token; ++corners)
        checkCorner(token, counts, max, line, where);
      if (corners < 3)
        throw InvalidInputError(where + "face has " + std::to_string(corners) +
                                " corners (the file may be cut short); faces need at least 3: "
                                "complete or remove the 'f' line");
      result.faceLines.push_back(line);
    } else if (keyword == "mtllib") {
      bool found = false;
      std::string names, name;
      while (words >> name) {
        found = found || pathExists(folder / name);
        names += (names.empty() ? "'" : ", '") + name + "'";
      }
      if (!found)
        result.missingFiles.push_back(where + "the material library " + names +
                                      " named by 'mtllib' was not found in " + folder.string());
    }
  }
  for (size_t which = 0; which < 2; ++which)
    if (static_cast<size_t>(max[which].value) > counts[which])
      throw InvalidInputError(at(path, max[which].line) + "a face refers to " +
                              (which == 0 ? "vertex " : "texture coordinate ") +
                              std::to_string(max[which].value) + " but the file has " +
                              std::to_string(counts[which]) +
                              " (1-based); fix the 'f' line or re-export the mesh");
  return result;
}

}  // namespace texgrad::obj
