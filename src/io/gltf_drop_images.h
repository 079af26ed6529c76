// glTF write-back helper (private to the io module): removing images from a model together with
// the textures and material references that use them, so no reference is left dangling.
#pragma once

#include <tiny_gltf.h>

#include <vector>

namespace texgrad::gltf {

/// Removes the images whose indices are in `dropped` from `model`, every texture that uses one of
/// them (as its source or as an extension's "source"), and every material reference to such a
/// texture: a core slot (baseColor, normal, ...) is left without a texture, and a texture-info
/// object inside a material extension (an object whose "index" names the texture) is removed.
/// The remaining images and textures are renumbered everywhere the model refers to them
/// (texture sources, material slots, "source"/"index" members in texture/material extensions).
void dropImages(tinygltf::Model& model, const std::vector<int>& dropped);

}  // namespace texgrad::gltf
