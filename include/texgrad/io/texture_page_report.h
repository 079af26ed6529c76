// The texture pages of every slot of a mesh as `texgrad info` and Python's Mesh.atlas_report
// report them: found and measured without reading a texel, problems collected rather than thrown.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "texgrad/io/texture_pages.h"
#include "texgrad/io/textured_mesh.h"

namespace texgrad {

/// One texture slot's pages (findTexturePages), each page's image size when its header can be
/// read (0 otherwise), and one line per problem (a missing page image, a face no page holds).
struct SlotPages {
  std::string slot;
  PageLayout layout;
  std::vector<std::string> problems;
};

/// The pages of every slot `mesh` names, in the order of its textures; of `texture` alone (slot
/// "baseColor") when `texture` holds a UDIM token, of none when it is another file.
std::vector<SlotPages> reportTexturePages(const TexturedMesh& mesh,
                                          const std::filesystem::path& texture = {});

/// The layout of `slot` in `pages` if its pages were found and hold every face of the mesh
/// (facePage filled), else nullptr.
const PageLayout* slotLayout(const std::vector<SlotPages>& pages, const std::string& slot);

}  // namespace texgrad
