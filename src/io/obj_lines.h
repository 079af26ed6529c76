// Line-level checks of an OBJ file before tinyobjloader reads it (private to the io module):
// tinyobjloader drops short faces, reads non-numbers as 0 and ignores a missing .mtl silently.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace texgrad::obj {

/// What the line scan learned that tinyobjloader does not report.
struct ObjLines {
  std::vector<size_t> faceLines;          ///< 1-based line number of each 'f' line, in file order
  std::vector<std::string> missingFiles;  ///< one sentence per 'mtllib' whose files are all absent
};

/// Scans `path` line by line; throws InvalidInputError naming the file and line for a 'v'/'vt'
/// coordinate that is not a finite number, an 'f' line with fewer than three corners, a corner
/// that is not 'v[/vt][/vn]' with non-zero integers, or an index past the last 'v'/'vt' line.
ObjLines scanObjLines(const std::filesystem::path& path);

}  // namespace texgrad::obj
