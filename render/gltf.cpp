// SPDX-License-Identifier: Apache-2.0
#include "render/gltf.h"

#include <assimp/BaseImporter.h>
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "render/scene_portals.h"

namespace envpis::render {

namespace fs = std::filesystem;
using nlohmann::json;

SceneMaterial make_pbr_scene_material(std::string name, std::shared_ptr<const PbrMaterial> pbr) {
  SceneMaterial m;
  m.name = std::move(name);
  pbr->assemble({0.5f, 0.5f}, &m.bsdf);
  m.transmissive = pbr->transmissive();
  m.emission = pbr->params().emissive;
  m.pbr = std::move(pbr);
  return m;
}

namespace {

/// One line whatever the message: assimp's and OpenImageIO's may span several (line breaks become "; ").
[[noreturn]] void fail(const std::string& path, const std::string& what) {
  std::string line = path + ": ";
  for (std::size_t i = 0; i < what.size(); ++i) {
    if (what[i] != '\n' && what[i] != '\r') line += what[i];
    else if (i + 1 < what.size() && what[i + 1] != '\n' && what[i + 1] != '\r') line += "; ";
  }
  throw Error(line);
}

std::vector<std::uint8_t> read_bytes(const std::string& path, const std::string& what) {
  // Regular files only: a URI naming /dev/zero, a FIFO or a directory would read forever, block or fail late.
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw Error(what + ": '" + path + "' is not a readable file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(what + ": cannot open '" + path + "'");
  return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), {});
}

std::vector<std::uint8_t> base64_decode(const std::string& s, std::size_t start) {
  auto value = [](char c) -> int {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+' || c == '-') return 62;
    if (c == '/' || c == '_') return 63;
    return -1;
  };
  std::vector<std::uint8_t> out;
  unsigned acc = 0;
  int bits = 0;
  for (std::size_t i = start; i < s.size() && s[i] != '='; ++i) {
    const int v = value(s[i]);
    if (v < 0) throw Error("invalid base64 data");
    acc = (acc << 6) | unsigned(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(std::uint8_t((acc >> bits) & 0xff));
    }
  }
  return out;
}

/// The file's JSON and, for a .glb, its BIN chunk.
struct Document {
  std::string path;
  fs::path dir;
  json j;
  std::vector<std::uint8_t> glb_bin;
  std::map<std::size_t, std::vector<std::uint8_t>> buffers;  // loaded on demand

  explicit Document(const std::string& file) : path(file), dir(fs::path(file).parent_path()) {
    const std::vector<std::uint8_t> bytes = read_bytes(file, file);
    auto u32 = [&](std::size_t at) {
      std::uint32_t v;
      std::memcpy(&v, &bytes[at], 4);
      return v;
    };
    try {
      if (bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0) {
        if (bytes.size() < 20) fail(file, "truncated GLB header");
        if (u32(4) != 2) fail(file, "GLB version " + std::to_string(u32(4)) + " (expected 2)");
        const std::size_t json_len = u32(12);
        if (u32(16) != 0x4E4F534Au || 20 + json_len > bytes.size()) fail(file, "GLB without a valid JSON chunk");
        j = json::parse(bytes.begin() + 20, bytes.begin() + 20 + std::ptrdiff_t(json_len));
        std::size_t at = 20 + ((json_len + 3) & ~std::size_t(3));
        if (at + 8 <= bytes.size() && u32(at + 4) == 0x004E4942u) {
          const std::size_t bin_len = u32(at);
          if (at + 8 + bin_len > bytes.size()) fail(file, "GLB BIN chunk runs past the end of the file");
          glb_bin.assign(bytes.begin() + std::ptrdiff_t(at + 8), bytes.begin() + std::ptrdiff_t(at + 8 + bin_len));
        }
      } else {
        j = json::parse(bytes.begin(), bytes.end());
      }
    } catch (const json::exception& e) {
      fail(file, std::string("invalid glTF JSON: ") + e.what());
    }
    if (!j.is_object()) fail(file, "the glTF JSON is not an object");
    // glTF 2.0 only (glTF 1.0 files would otherwise go through assimp's guessing, see keep_only_gltf2).
    const json* version = j.contains("asset") && j["asset"].is_object() && j["asset"].contains("version")
                              ? &j["asset"]["version"] : nullptr;
    if (!version || !version->is_string() || version->get<std::string>().rfind("2.", 0) != 0)
      fail(file, "not a glTF 2.0 file (asset.version " + (version ? version->dump() : std::string("missing")) + ")");
  }

  // The accessors below throw Error without the file's name: load_gltf adds it (and the material's).

  /// Element `index` of the top-level array `key`.
  const json& at(const char* key, const json& index) const {
    if (!index.is_number_unsigned() || !j.contains(key) || !j[key].is_array() || index.get<std::size_t>() >= j[key].size())
      throw Error(std::string("invalid ") + key + " index");
    return j[key][index.get<std::size_t>()];
  }

  std::vector<std::uint8_t> uri_bytes(const std::string& uri) const {
    if (uri.rfind("data:", 0) == 0) {
      const std::size_t comma = uri.find(";base64,");
      if (comma == std::string::npos) throw Error("a data URI that is not base64");
      return base64_decode(uri, comma + 8);
    }
    if (uri.find("://") != std::string::npos) throw Error("remote URI '" + uri + "' (only local files)");
    return read_bytes((dir / uri).string(), "URI '" + uri + "'");
  }

  const std::vector<std::uint8_t>& buffer(const json& index) {
    const json& b = at("buffers", index);
    const std::size_t i = index.get<std::size_t>();
    auto it = buffers.find(i);
    if (it != buffers.end()) return it->second;
    std::vector<std::uint8_t> data;
    if (b.contains("uri") && b["uri"].is_string()) data = uri_bytes(b["uri"].get<std::string>());
    else if (i == 0) data = glb_bin;
    else throw Error("buffer " + std::to_string(i) + " has no data");
    return buffers.emplace(i, std::move(data)).first->second;
  }

  std::vector<std::uint8_t> image_bytes(const json& image) {
    if (image.contains("uri") && image["uri"].is_string()) return uri_bytes(image["uri"].get<std::string>());
    if (!image.contains("bufferView")) throw Error("an image without uri or bufferView");
    const json& view = at("bufferViews", image["bufferView"]);
    const std::vector<std::uint8_t>& buf = buffer(view.value("buffer", json()));
    const std::size_t off = view.value("byteOffset", std::size_t(0)), len = view.value("byteLength", std::size_t(0));
    if (off + len > buf.size() || off + len < off) throw Error("an image's bufferView runs past its buffer");
    return std::vector<std::uint8_t>(buf.begin() + std::ptrdiff_t(off), buf.begin() + std::ptrdiff_t(off + len));
  }
};

float number(const json& o, const char* key, float def) {
  if (!o.is_object() || !o.contains(key)) return def;
  if (!o[key].is_number()) throw Error(std::string("'") + key + "' is not a number");
  return o[key].get<float>();
}

Rgb color(const json& o, const char* key, Rgb def) {
  if (!o.is_object() || !o.contains(key)) return def;
  const json& a = o[key];
  if (!a.is_array() || a.size() < 3 || !a[0].is_number() || !a[1].is_number() || !a[2].is_number())
    throw Error(std::string("'") + key + "' is not an array of numbers");
  return {a[0].get<float>(), a[1].get<float>(), a[2].get<float>()};
}

class MaterialReader {
 public:
  explicit MaterialReader(Document& doc) : doc_(doc) {}

  std::shared_ptr<const PbrMaterial> read(const json& m) {
    PbrParams p;
    PbrTextures t;
    const json pbr = m.value("pbrMetallicRoughness", json::object());
    p.base_color = color(pbr, "baseColorFactor", {1, 1, 1});
    p.metallic = number(pbr, "metallicFactor", 1.0f);
    p.roughness = number(pbr, "roughnessFactor", 1.0f);
    t.base_color = texture(pbr, "baseColorTexture", true);
    t.metallic_roughness = texture(pbr, "metallicRoughnessTexture", false);
    t.normal = texture(m, "normalTexture", false);
    if (m.contains("normalTexture")) t.normal_scale = number(m["normalTexture"], "scale", 1.0f);
    t.emissive = texture(m, "emissiveTexture", true);
    p.emissive = color(m, "emissiveFactor", {0, 0, 0});
    const json ext = m.value("extensions", json::object());
    if (ext.contains("KHR_materials_emissive_strength"))
      p.emissive = p.emissive * number(ext["KHR_materials_emissive_strength"], "emissiveStrength", 1.0f);
    if (ext.contains("KHR_materials_clearcoat")) {
      p.clearcoat = number(ext["KHR_materials_clearcoat"], "clearcoatFactor", 0.0f);
      p.clearcoat_roughness = number(ext["KHR_materials_clearcoat"], "clearcoatRoughnessFactor", 0.0f);
    }
    if (ext.contains("KHR_materials_transmission"))
      p.transmission = number(ext["KHR_materials_transmission"], "transmissionFactor", 0.0f);
    if (ext.contains("KHR_materials_ior")) p.ior = number(ext["KHR_materials_ior"], "ior", 1.5f);
    return std::make_shared<const PbrMaterial>(p, std::move(t));
  }

 private:
  TextureRef texture(const json& parent, const char* key, bool srgb) {
    TextureRef r;
    if (!parent.is_object() || !parent.contains(key)) return r;
    const json& info = parent[key];
    if (!info.is_object() || !info.contains("index")) throw Error(std::string(key) + " without a texture index");
    int texcoord = info.value("texCoord", 0);
    const json& tex = doc_.at("textures", info["index"]);
    if (tex.contains("sampler")) {
      const json& s = doc_.at("samplers", tex["sampler"]);
      r.wrap_s = wrap_from_gltf(s.value("wrapS", 10497));
      r.wrap_t = wrap_from_gltf(s.value("wrapT", 10497));
    }
    if (info.contains("extensions") && info["extensions"].contains("KHR_texture_transform")) {
      const json& x = info["extensions"]["KHR_texture_transform"];
      if (x.contains("offset")) r.transform.offset = {x["offset"].at(0).get<float>(), x["offset"].at(1).get<float>()};
      if (x.contains("scale")) r.transform.scale = {x["scale"].at(0).get<float>(), x["scale"].at(1).get<float>()};
      r.transform.rotation = number(x, "rotation", 0.0f);
      texcoord = x.value("texCoord", texcoord);
    }
    if (texcoord != 0) throw Error(std::string(key) + " uses TEXCOORD_" + std::to_string(texcoord) + " (only TEXCOORD_0 is supported)");
    if (!tex.contains("source")) throw Error(std::string(key) + ": a texture without an image source");
    const std::size_t src = tex["source"].get<std::size_t>();
    auto& slot = cache_[{src, srgb}];
    if (!slot) slot = Texture::load_memory(doc_.image_bytes(doc_.at("images", tex["source"])), srgb,
                                           "image " + std::to_string(src));
    r.texture = slot;
    return r;
  }
  Document& doc_;
  std::map<std::pair<std::size_t, bool>, std::shared_ptr<const Texture>> cache_;
};

/// Leaves the importer with assimp's glTF 2.0 reader only. assimp hands a file that no reader claims
/// by its extension (or that the claiming readers reject, as the glTF 1.0 reader does with a glTF 2.0
/// file and vice versa) to the signature check of all of its ~50 readers (OBJ, PLY, X, ...); a .gltf
/// or .glb file should never reach third-party parsers of other formats.
void keep_only_gltf2(Assimp::Importer& importer) {
  std::vector<Assimp::BaseImporter*> others;
  for (std::size_t i = 0; i < importer.GetImporterCount(); ++i) {
    const aiImporterDesc* d = importer.GetImporterInfo(i);
    if (!d || std::strcmp(d->mName, "glTF2 Importer") != 0) others.push_back(importer.GetImporter(i));
  }
  for (Assimp::BaseImporter* imp : others) {
    importer.UnregisterLoader(imp);
    delete imp;  // unregistered readers are no longer the importer's to delete
  }
  if (importer.GetImporterCount() != 1) throw Error("assimp has no glTF 2.0 reader");
}

/// Files that crash assimp 5.2's glTF 2.0 reader, refused before it sees them (found by fuzz_gltf;
/// fuzz/README.md lists what is known about assimp and what is guarded here).
void refuse_assimp_crashes(const json& j, const std::string& path) {
  // A skin without inverseBindMatrices (optional in glTF: identity matrices) is dereferenced as a null
  // accessor when a node uses the skin.
  if (j.contains("skins") && j["skins"].is_array())
    for (std::size_t i = 0; i < j["skins"].size(); ++i)
      if (!j["skins"][i].is_object() || !j["skins"][i].contains("inverseBindMatrices"))
        fail(path, "skin " + std::to_string(i) + " without inverseBindMatrices (not supported)");
  // An embedded image's MIME type without a '/' ("mimeType" or a data: URI's media type): assimp takes
  // strchr(type, '/') + 1 as the file extension, address 1 when there is no '/'.
  if (j.contains("images") && j["images"].is_array())
    for (std::size_t i = 0; i < j["images"].size(); ++i) {
      const json& im = j["images"][i];
      if (!im.is_object()) continue;
      std::vector<std::string> types;
      if (im.contains("mimeType") && im["mimeType"].is_string()) types.push_back(im["mimeType"].get<std::string>());
      if (im.contains("uri") && im["uri"].is_string()) {
        const std::string uri = im["uri"].get<std::string>();
        if (uri.rfind("data:", 0) == 0) types.push_back(uri.substr(5, uri.find_first_of(";,") - 5));
      }
      for (const std::string& type : types)
        if (!type.empty() && type.find('/') == std::string::npos)
          fail(path, "image " + std::to_string(i) + " has the MIME type '" + type + "' (expected type/subtype)");
    }
}

/// glTF (+Y up) to the renderer's +Z up.
Vec3 y_up_to_z_up(aiVector3D v) { return {v.x, -v.z, v.y}; }

}  // namespace

bool is_portal_node(const std::string& name) { return name.rfind("portal", 0) == 0; }

namespace {

/// The portal quad of a node: its meshes' triangles in the renderer's frame, wound as in the file
/// (a mirroring transform M swaps the winding back, as for geometry).
Quad read_portal(const aiScene* sc, const aiNode* node, const aiMatrix4x4& M, bool mirror) {
  std::vector<Vec3> positions;
  std::vector<std::uint32_t> indices;
  for (unsigned k = 0; k < node->mNumMeshes; ++k) {
    if (node->mMeshes[k] >= sc->mNumMeshes) throw Error("refers to a missing mesh");
    const aiMesh* am = sc->mMeshes[node->mMeshes[k]];
    const std::uint32_t base = std::uint32_t(positions.size());
    for (unsigned v = 0; v < am->mNumVertices; ++v) positions.push_back(y_up_to_z_up(M * am->mVertices[v]));
    for (unsigned t = 0; t < am->mNumFaces; ++t) {
      const aiFace& f = am->mFaces[t];
      if (f.mNumIndices != 3) continue;
      for (unsigned q = 0; q < 3; ++q)
        if (f.mIndices[q] >= am->mNumVertices) throw Error("a face index is out of range");
      const unsigned b = mirror ? 2 : 1, c = mirror ? 1 : 2;
      indices.insert(indices.end(), {base + f.mIndices[0], base + f.mIndices[b], base + f.mIndices[c]});
    }
  }
  return quad_from_triangles(positions, indices);
}

GltfModel read_gltf(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) fail(path, "no such glTF file");
  Document doc(path);
  refuse_assimp_crashes(doc.j, path);
  Assimp::Importer importer;
  keep_only_gltf2(importer);
  const unsigned flags = aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_SortByPType |
                         aiProcess_GenSmoothNormals | aiProcess_ValidateDataStructure | aiProcess_FlipUVs;
  const aiScene* sc = importer.ReadFile(path, flags);
  if (!sc || (sc->mFlags & AI_SCENE_FLAGS_INCOMPLETE) || !sc->mRootNode)
    fail(path, std::string("cannot read glTF: ") +
                   (*importer.GetErrorString() ? importer.GetErrorString() : "no scene with a node"));

  GltfModel model;
  // Materials: glTF's, in file order (assimp keeps that order and appends a default material when a
  // mesh has none; a name match is preferred when assimp's names differ).
  const json mats = doc.j.value("materials", json::array());
  if (!mats.is_array()) fail(path, "'materials' is not an array");
  MaterialReader reader(doc);
  std::vector<int> of_ai(sc->mNumMaterials, -1);
  auto add_material = [&](const json& m, const std::string& name) {
    try {
      model.materials.push_back(make_pbr_scene_material(name, reader.read(m)));
    } catch (const Error& e) {
      fail(path, "material '" + name + "': " + e.what());
    } catch (const json::exception& e) {
      fail(path, "material '" + name + "': " + e.what());
    }
    return int(model.materials.size()) - 1;
  };
  for (unsigned i = 0; i < sc->mNumMaterials; ++i) {
    if (i < mats.size()) {
      const std::string name = mats[i].value("name", std::string());
      of_ai[i] = add_material(mats[i], name.empty() ? "material-" + std::to_string(i) : name);
    } else {
      of_ai[i] = add_material(json::object(), "default");
    }
  }
  // Names must be unique in a scene.
  std::map<std::string, int> seen;
  for (auto& m : model.materials)
    if (seen[m.name]++) m.name += "-" + std::to_string(seen[m.name] - 1);

  // Geometry: one mesh per material, node transforms applied.
  std::map<int, std::size_t> part_of;
  Portals checked;  // the portals read so far, validated as the scene will hold them
  std::vector<std::pair<const aiNode*, aiMatrix4x4>> stack{{sc->mRootNode, sc->mRootNode->mTransformation}};
  int depth_guard = 0;
  while (!stack.empty()) {
    if (++depth_guard > 1000000) fail(path, "node tree too large or recursive");
    auto [node, M] = stack.back();
    stack.pop_back();
    for (unsigned c = 0; c < node->mNumChildren; ++c)
      stack.push_back({node->mChildren[c], M * node->mChildren[c]->mTransformation});
    aiMatrix3x3 N(M);
    N.Inverse().Transpose();
    const bool mirror = aiMatrix3x3(M).Determinant() < 0;
    const bool portal = is_portal_node(node->mName.C_Str()) && node->mNumMeshes > 0;
    if (portal) {
      const std::string where = "portal node '" + std::string(node->mName.C_Str()) + "'";
      try {
        model.portals.push_back({node->mName.C_Str(), read_portal(sc, node, M, mirror)});
      } catch (const Error& e) {
        fail(path, where + ": " + e.what());
      }
      add_portal(checked, model.portals.back().quad, path + ": " + where);
    }
    for (unsigned k = 0; !portal && k < node->mNumMeshes; ++k) {
      if (node->mMeshes[k] >= sc->mNumMeshes) fail(path, "node refers to a missing mesh");
      const aiMesh* am = sc->mMeshes[node->mMeshes[k]];
      if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
      if (am->mMaterialIndex >= of_ai.size()) fail(path, "mesh refers to a missing material");
      const int mat = of_ai[am->mMaterialIndex];
      auto [it, fresh] = part_of.emplace(mat, model.parts.size());
      if (fresh) model.parts.push_back({model.materials[std::size_t(mat)].name, {}, mat});
      TriangleMesh& m = model.parts[it->second].mesh;
      const std::uint32_t base = std::uint32_t(m.positions.size());
      const bool uv = am->HasTextureCoords(0);
      // Parts with and without UVs may share a material: the UV-less vertices get (0, 0).
      if (uv && m.uvs.size() < m.positions.size()) m.uvs.resize(m.positions.size(), {0, 0});
      for (unsigned v = 0; v < am->mNumVertices; ++v) {
        m.positions.push_back(y_up_to_z_up(M * am->mVertices[v]));
        // A non-finite normal (in the file, or overflowing the node transform) counts as none: (0, 0, 0).
        const Vec3 n = am->HasNormals() ? y_up_to_z_up(N * am->mNormals[v]) : Vec3{0, 0, 0};
        m.normals.push_back(std::isfinite(n.x) && std::isfinite(n.y) && std::isfinite(n.z) ? n : Vec3{0, 0, 0});
        if (uv) m.uvs.push_back({am->mTextureCoords[0][v].x, am->mTextureCoords[0][v].y});
        else if (!m.uvs.empty()) m.uvs.push_back({0, 0});
      }
      for (unsigned t = 0; t < am->mNumFaces; ++t) {
        const aiFace& f = am->mFaces[t];
        if (f.mNumIndices != 3) continue;
        for (unsigned q = 0; q < 3; ++q)
          if (f.mIndices[q] >= am->mNumVertices) fail(path, "a face index is out of range");
        if (mirror) m.indices.insert(m.indices.end(), {base + f.mIndices[0], base + f.mIndices[2], base + f.mIndices[1]});
        else m.indices.insert(m.indices.end(), {base + f.mIndices[0], base + f.mIndices[1], base + f.mIndices[2]});
      }
    }
    // The first camera in the tree (assimp names a camera after its node).
    if (!model.camera) {
      for (unsigned c = 0; c < sc->mNumCameras; ++c) {
        const aiCamera* cam = sc->mCameras[c];
        if (cam->mName != node->mName) continue;
        CameraSpec spec;
        const aiVector3D from = M * cam->mPosition, to = M * (cam->mPosition + cam->mLookAt);
        spec.from = y_up_to_z_up(from);
        spec.to = y_up_to_z_up(to);
        spec.up = y_up_to_z_up(aiMatrix3x3(M) * cam->mUp);
        const json cams = doc.j.value("cameras", json::array());
        float aspect = cam->mAspect > 0 ? cam->mAspect : 16.0f / 9.0f;
        if (c < cams.size() && cams[c].value("type", "") == "perspective") {
          const json p = cams[c].value("perspective", json::object());
          spec.vfov_degrees = number(p, "yfov", 0.7f) * 180.0f / kPi;
          aspect = number(p, "aspectRatio", aspect);
        } else if (c < cams.size() && cams[c].value("type", "") == "orthographic") {
          spec.projection = Projection::Orthographic;
          spec.ortho_height = 2 * number(cams[c].value("orthographic", json::object()), "ymag", 1.0f);
        }
        spec.width = 640;
        spec.height = std::max(1, int(std::lround(640 / std::clamp(aspect, 0.1f, 10.0f))));
        model.camera = spec;
        break;
      }
    }
  }
  if (model.parts.empty()) fail(path, "no triangle mesh");
  for (const GltfModel::Part& p : model.parts) {
    for (const Vec3& v : p.mesh.positions)
      if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z)) fail(path, "a non-finite vertex position");
    for (const Point2& uv : p.mesh.uvs)
      if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) fail(path, "a non-finite texture coordinate");
  }
  return model;
}

}  // namespace

GltfModel load_gltf(const std::string& path) {
  // Every problem as one Error that names the file (JSON type errors included).
  try {
    return read_gltf(path);
  } catch (const json::exception& e) {
    fail(path, std::string("invalid glTF: ") + e.what());
  } catch (const Error& e) {
    if (std::string(e.what()).rfind(path, 0) == 0) throw;
    fail(path, e.what());
  }
}

}  // namespace envpis::render
