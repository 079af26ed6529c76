// The texture pages of every slot, as reports list them (texture_page_report.h).
#include "texgrad/io/texture_page_report.h"

#include <algorithm>
#include <tuple>

#include "texgrad/core/error.h"

namespace texgrad {

std::vector<SlotPages> reportTexturePages(const TexturedMesh& mesh,
                                          const std::filesystem::path& texture) {
  std::vector<std::string> slots;
  if (hasUdimToken(texture)) slots.push_back("baseColor");
  for (const TextureRef& t : mesh.textures)
    if (texture.empty() && std::find(slots.begin(), slots.end(), t.slot) == slots.end())
      slots.push_back(t.slot);
  std::vector<SlotPages> all;
  for (const std::string& slot : slots) {
    SlotPages pages{slot, {}, {}};
    try {
      pages.layout = findTexturePages(mesh, slot, hasUdimToken(texture) ? texture : "");
    } catch (const Error& e) {
      pages.problems.push_back(e.what());
      all.push_back(std::move(pages));
      continue;
    }
    for (size_t p = 0; p < pages.layout.pages.size(); ++p) {
      TexturePage& page = pages.layout.pages[p];
      try {
        std::tie(page.width, page.height) = readPageSize(pages.layout, mesh, p);
      } catch (const Error& e) {
        pages.problems.push_back(e.what());
      }
    }
    all.push_back(std::move(pages));
  }
  return all;
}

const PageLayout* slotLayout(const std::vector<SlotPages>& pages, const std::string& slot) {
  for (const SlotPages& s : pages)
    if (s.slot == slot && !s.layout.facePage.empty()) return &s.layout;
  return nullptr;
}

}  // namespace texgrad
