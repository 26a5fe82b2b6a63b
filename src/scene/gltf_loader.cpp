#include "scene/gltf_loader.h"

#include <tiny_gltf.h>

#include <filesystem>
#include <fstream>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <map>
#include <set>

#include "core/error.h"
#include "materials/bsdf.h"
#include "geometry/instances.h"
#include "scene/gltf_asset.h"
#include "scene/gltf_extensions.h"
#include "scene/gltf_files.h"
#include "scene/gltf_lights.h"
#include "scene/gltf_components.h"
#include "scene/gltf_textures.h"
#include "scene/mesh_loader.h"
#include "scene/tangents.h"

namespace tessera {
namespace {

namespace gl = tinygltf;

/// Component types of vertex attributes: FLOAT and those KHR_mesh_quantization adds.
constexpr std::initializer_list<int> kFloatOrQuantized = {TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_BYTE,
                                                          TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_SHORT,
                                                          TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT};

/// How deep TESSERA_asset_gltf assets may name further assets (a cycle of assets stops here).
constexpr int kMaxAssetNesting = 8;

class Loader {
public:
    /// `root` places the file's scene (identity for a scene; the naming node's world transform for
    /// a TESSERA_asset_gltf asset, which `nesting` counts); `assetBytes` is the scene's running total
    /// of asset bytes read (null: this loader keeps its own).
    Loader(std::string path, std::vector<std::string>& warnings, const SceneLoadOptions& options, const Mat4d& root = Mat4d(1.0),
           int nesting = 0, uint64_t* assetBytes = nullptr)
        : path_(std::move(path)), warnings_(warnings), options_(options), root_(root), nesting_(nesting),
          assetBytes_(assetBytes ? assetBytes : &ownAssetBytes_) {}

    Scene load() {
        Scene scene = loadUnfinalized();
        scene.finalize();
        return scene;
    }

    /// The scene before Scene::finalize: what TESSERA_asset_gltf merges into the scene naming it.
    /// An asset's TESSERA_render settings are not read.
    Scene loadUnfinalized() {
        readModel();
        checkRequiredExtensions();
        warnUnsupportedExtensions();
        scene_.sourcePath = path_;
        if (nesting_ == 0) {
            readRenderSettings();
            readGltfEnvironment(model_, values_, options_, *assetBytes_, scene_);  // an imported asset's own environment is not the scene's
        }
        readMaterials();
        traverseScene();
        if (droppedTriangles_ > 0)
            warnings_.push_back(path_ + ": dropped " + std::to_string(droppedTriangles_) +
                                " degenerate or non-finite triangle(s)");
        return std::move(scene_);
    }

private:
    [[noreturn]] void fail(const std::string& element, const std::string& problem) const {
        throw SceneError(path_, element, problem);
    }

    void readModel() {
        std::error_code ec;
        if (!std::filesystem::is_regular_file(path_, ec)) fail("", "no such file");
        gl::TinyGLTF loader;
        // tinygltf's decoders never see an image: the callback keeps the bytes for decodeImage.
        loader.SetImageLoader(storeImageBytes, nullptr);
        access_.root = std::filesystem::weakly_canonical(std::filesystem::absolute(path_), ec).parent_path();
        access_.options = options_;
        loader.SetFsCallbacks(access_.callbacks());
        // The scene file itself is always readable, wherever it is; only what it references is confined.
        uint64_t sceneBytes = std::filesystem::file_size(path_, ec);
        if (!ec && sceneBytes > options_.maxFileBytes)
            fail("", "file is " + std::to_string(sceneBytes) + " bytes, over the limit of " + std::to_string(options_.maxFileBytes));
        std::string err, warn;
        std::string ext = std::filesystem::path(path_).extension().string();
        for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
        bool ok = ext == ".glb" ? loader.LoadBinaryFromFile(&model_, &err, &warn, path_)
                                : loader.LoadASCIIFromFile(&model_, &err, &warn, path_);
        if (!ok || !err.empty()) {
            if (!access_.violation.empty()) fail("buffers", access_.violation);
            std::string msg = err.empty() ? "cannot parse the file" : err;
            while (!msg.empty() && (msg.back() == '\n' || msg.back() == ' ')) msg.pop_back();
            for (char& c : msg)
                if (c == '\n') c = ';';
            fail("", "invalid glTF: " + msg);
        }
    }

    void checkRequiredExtensions() const {
        std::vector<std::string> known = supportedGltfExtensions();
        for (const std::string& e : model_.extensionsRequired)
            if (std::find(known.begin(), known.end(), e) == known.end()) {
                std::string what = unsupportedExtensionEffect(e).required;
                fail("extensionsRequired", "unsupported required extension '" + e + "'" + (what.empty() ? "" : ": " + what));
            }
    }

    /// One warning line per extension of extensionsUsed that Tessera does not implement, saying what
    /// is ignored; then the ignored core features (one line each). A file that is not renderable
    /// without an unsupported extension names it in extensionsRequired (an error, above); the
    /// exception is a primitive that exists only in Draco-compressed form, refused here.
    void warnUnsupportedExtensions() const {
        std::vector<std::string> known = supportedGltfExtensions();
        for (const std::string& e : model_.extensionsUsed) {
            if (std::find(known.begin(), known.end(), e) != known.end()) continue;
            if (std::find(model_.extensionsRequired.begin(), model_.extensionsRequired.end(), e) != model_.extensionsRequired.end())
                continue;
            warnings_.push_back(path_ + ": extensionsUsed: '" + e + "' is not supported: " + unsupportedExtensionEffect(e).ignored);
        }
        bool colors = false, morphs = false;
        for (size_t m = 0; m < model_.meshes.size(); ++m)
            for (size_t p = 0; p < model_.meshes[m].primitives.size(); ++p) {
                const gl::Primitive& prim = model_.meshes[m].primitives[p];
                colors = colors || prim.attributes.count("COLOR_0") > 0;
                morphs = morphs || !prim.targets.empty();
                auto draco = prim.extensions.find("KHR_draco_mesh_compression");
                auto pos = prim.attributes.find("POSITION");
                if (draco != prim.extensions.end() && pos != prim.attributes.end() && pos->second >= 0 &&
                    size_t(pos->second) < model_.accessors.size() && model_.accessors[size_t(pos->second)].bufferView < 0)
                    fail(indexedElement("meshes", m) + "." + indexedElement("primitives", p),
                         "exists only Draco-compressed (KHR_draco_mesh_compression is not supported): " +
                             unsupportedExtensionEffect("KHR_draco_mesh_compression").required);
            }
        auto ignored = [&](bool present, const std::string& what) {
            if (present) warnings_.push_back(path_ + ": " + what);
        };
        ignored(colors, "vertex colours (COLOR_0) are ignored: base colour comes from the material alone");
        ignored(morphs, "morph targets are ignored: meshes are rendered in their base shape");
        ignored(!model_.skins.empty(), "skins are ignored: skinned meshes are rendered in their bind pose");
        ignored(!model_.animations.empty(), "animations are ignored: nodes are rendered in their static transforms");
    }

    Rgb color3(const gl::Value& obj, const char* key, const std::string& element, Rgb fallback, double maxComponent) const {
        return values_.color3(obj, key, element, fallback, maxComponent);
    }
    double number(const gl::Value& obj, const char* key, const std::string& element, double fallback) const {
        return values_.number(obj, key, element, fallback);
    }


    void readRenderSettings() {
        auto it = model_.extensions.find("TESSERA_render");
        if (it == model_.extensions.end()) return;
        const gl::Value& v = it->second;
        const std::string el = "extensions.TESSERA_render";
        if (!v.IsObject()) fail(el, "must be an object");
        RenderSettings& s = scene_.settings;
        if (v.Has("resolution")) {
            const gl::Value& r = v.Get("resolution");
            if (!r.IsArray() || r.ArrayLen() != 2 || !r.Get(0).IsNumber() || !r.Get(1).IsNumber())
                fail(el, "'resolution' must be [width, height]");
            double w = r.Get(0).GetNumberAsDouble(), h = r.Get(1).GetNumberAsDouble();
            if (!(w >= 1 && h >= 1 && w <= 65536 && h <= 65536) || w != std::floor(w) || h != std::floor(h))
                fail(el, "'resolution' must be two integers in [1, 65536]");
            s.width = int(w);
            s.height = int(h);
        }
        double spp = number(v, "spp", el, s.spp);
        if (!(spp >= 1 && spp <= 1e9)) fail(el, "'spp' must be in [1, 1e9]");
        s.spp = int(spp);
        double depth = number(v, "maxDepth", el, s.maxDepth);
        if (!(depth >= -1 && depth <= 1e6)) fail(el, "'maxDepth' must be -1 (unlimited) or a bounce count");
        s.maxDepth = int(depth);
        double seed = number(v, "seed", el, 0.0);
        if (seed < 0) fail(el, "'seed' must be non-negative");
        s.seed = uint64_t(seed);
        if (v.Has("integrator")) {
            if (!v.Get("integrator").IsString()) fail(el, "'integrator' must be a string");
            s.integrator = v.Get("integrator").Get<std::string>();
        }
    }

    void readMaterials() {
        // Decoded images together stay under --max-memory (which sets maxFileBytes).
        GltfTextureReader textures(model_, path_, scene_.images, warnings_,
                                   [this](const std::string& p) { return access_.whyRefused(p); },
                                   options_.maxFileBytes);
        for (size_t i = 0; i < model_.materials.size(); ++i) {
            const gl::Material& gm = model_.materials[i];
            const std::string el = indexedElement("materials", i);
            Material m;
            m.name = gm.name.empty() ? el : gm.name;
            const std::vector<double>& bc = gm.pbrMetallicRoughness.baseColorFactor;
            if (bc.size() < 3) fail(el, "baseColorFactor must have 4 components");
            for (int c = 0; c < 3; ++c) {
                if (!(bc[c] >= 0.0 && bc[c] <= 1.0)) fail(el, "baseColorFactor components must be in [0, 1]");
                m.bsdf.baseColor[c] = float(bc[c]);
            }
            double metallic = gm.pbrMetallicRoughness.metallicFactor;
            double roughness = gm.pbrMetallicRoughness.roughnessFactor;
            if (!(metallic >= 0 && metallic <= 1)) fail(el, "metallicFactor must be in [0, 1]");
            if (!(roughness >= 0 && roughness <= 1)) fail(el, "roughnessFactor must be in [0, 1]");
            double transmission = 0.0, ior = 1.5, strength = 1.0;
            if (auto t = gm.extensions.find("KHR_materials_transmission"); t != gm.extensions.end())
                transmission = number(t->second, "transmissionFactor", el + ".extensions.KHR_materials_transmission", 0.0);
            if (auto t = gm.extensions.find("KHR_materials_ior"); t != gm.extensions.end()) {
                ior = number(t->second, "ior", el + ".extensions.KHR_materials_ior", 1.5);
                if (!(ior >= 1.0 && ior <= 10.0)) fail(el + ".extensions.KHR_materials_ior", "ior must be in [1, 10]");
            }
            if (auto t = gm.extensions.find("KHR_materials_emissive_strength"); t != gm.extensions.end()) {
                strength = number(t->second, "emissiveStrength", el + ".extensions.KHR_materials_emissive_strength", 1.0);
                if (strength < 0) fail(el + ".extensions.KHR_materials_emissive_strength", "emissiveStrength must be >= 0");
            }
            if (auto t = gm.extensions.find("KHR_materials_specular"); t != gm.extensions.end()) {
                const std::string sel = el + ".extensions.KHR_materials_specular";
                double f = number(t->second, "specularFactor", sel, 1.0);
                if (!(f >= 0.0 && f <= 1.0)) fail(sel, "specularFactor must be in [0, 1]");
                m.bsdf.specular = float(f);
                m.bsdf.specularColor = color3(t->second, "specularColorFactor", sel, Rgb(1.f), 1e30);
            }
            if (auto t = gm.extensions.find("KHR_materials_volume"); t != gm.extensions.end()) {
                const std::string vel = el + ".extensions.KHR_materials_volume";
                double thickness = number(t->second, "thicknessFactor", vel, 0.0);
                if (!(thickness >= 0.0) || !std::isfinite(thickness)) fail(vel, "thicknessFactor must be finite and >= 0");
                double distance = number(t->second, "attenuationDistance", vel, kInfinity);
                if (!(distance > 0.0)) fail(vel, "attenuationDistance must be > 0");
                Rgb color = color3(t->second, "attenuationColor", vel, Rgb(1.f), 1.0);
                m.bsdf.thinWalled = thickness == 0.0;
                // Beer–Lambert: attenuationColor is the transmittance after attenuationDistance,
                // so σa = −ln(color) / distance (KHR_materials_volume).
                if (!m.bsdf.thinWalled && std::isfinite(distance))
                    for (int c = 0; c < 3; ++c) m.bsdf.attenuationCoeff[c] = float(-std::log(std::max(double(color[c]), 1e-30)) / distance);
            }
            m.bsdf.metallic = float(metallic);
            m.bsdf.alpha = float(roughness * roughness);
            m.bsdf.transmission = float(transmission);
            m.bsdf.ior = float(ior);
            finalizeBsdfParams(m.bsdf);
            if (gm.emissiveFactor.size() >= 3) {
                for (int c = 0; c < 3; ++c) {
                    double e = gm.emissiveFactor[c] * strength;
                    if (!(e >= 0.0) || !std::isfinite(e)) fail(el, "emission must be finite and non-negative");
                    m.emission[c] = float(e);
                }
            }
            m.doubleSided = gm.doubleSided;
            textures.readMaterial(gm, m, el);
            alphaMasks_.push_back(GltfTextureReader::alphaMaskOf(m));
            scene_.materials.push_back(m);
        }
        // Primitives without a material get glTF's "default material" (baseColor 1, metallic 1)
        // replaced by a grey Lambertian: a white rough metal is never what an untextured mesh means.
        defaultMaterial_ = uint32_t(scene_.materials.size());
        Material def;
        def.name = "default";
        def.bsdf.baseColor = Rgb(0.8f);
        def.bsdf.specular = 0.f;  // Lambertian: no dielectric coat (KHR_materials_specular's specularFactor 0)
        finalizeBsdfParams(def.bsdf);
        scene_.materials.push_back(def);
        alphaMasks_.push_back(nullptr);
    }

    Mat4d localTransform(const gl::Node& node, const std::string& el) const {
        if (node.matrix.size() == 16) {
            Mat4d m;
            for (int c = 0; c < 4; ++c)
                for (int r = 0; r < 4; ++r) m[c][r] = node.matrix[size_t(c * 4 + r)];  // column-major
            return m;
        }
        if (!node.matrix.empty()) fail(el, "matrix must have 16 numbers");
        Mat4d t(1.0);
        if (!node.translation.empty()) {
            if (node.translation.size() != 3) fail(el, "translation must have 3 numbers");
            t = glm::translate(Mat4d(1.0), Vec3d(node.translation[0], node.translation[1], node.translation[2]));
        }
        if (!node.rotation.empty()) {
            if (node.rotation.size() != 4) fail(el, "rotation must have 4 numbers");
            glm::dquat q(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);  // w, x, y, z
            double len = glm::length(q);
            if (!(len > 0.0) || !std::isfinite(len)) fail(el, "rotation must be a non-zero quaternion");
            t = t * glm::mat4_cast(q / len);
        }
        if (!node.scale.empty()) {
            if (node.scale.size() != 3) fail(el, "scale must have 3 numbers");
            t = glm::scale(t, Vec3d(node.scale[0], node.scale[1], node.scale[2]));
        }
        for (int c = 0; c < 4; ++c)
            for (int r = 0; r < 4; ++r)
                if (!std::isfinite(t[c][r])) fail(el, "transform must be finite");
        return t;
    }

    void traverseScene() {
        std::vector<int> roots;
        if (!model_.scenes.empty()) {
            int s = model_.defaultScene >= 0 ? model_.defaultScene : 0;
            if (s >= int(model_.scenes.size())) fail("scene", "default scene index out of range");
            roots = model_.scenes[size_t(s)].nodes;
        } else {
            // No scenes array: render every node that is nobody's child.
            std::vector<bool> isChild(model_.nodes.size(), false);
            for (const gl::Node& n : model_.nodes)
                for (int c : n.children)
                    if (c >= 0 && size_t(c) < isChild.size()) isChild[size_t(c)] = true;
            for (size_t i = 0; i < model_.nodes.size(); ++i)
                if (!isChild[i]) roots.push_back(int(i));
        }
        countReferences();
        for (int r : roots) visitNode(r, root_, 0);
    }

    void visitNode(int index, const Mat4d& parent, int depth) {
        const std::string el = indexedElement("nodes", size_t(std::max(index, 0)));
        if (index < 0 || size_t(index) >= model_.nodes.size()) fail(el, "node index out of range");
        // glTF requires the node hierarchy to be a forest; a cycle or a shared child would otherwise
        // recurse forever or duplicate geometry.
        if (!visited_.insert(index).second) fail(el, "node is reachable twice (cycle or shared child)");
        if (depth > 1024) fail(el, "node hierarchy deeper than 1024");
        const gl::Node& node = model_.nodes[size_t(index)];
        Mat4d world = parent * localTransform(node, el);
        if (node.mesh >= 0) readMesh(node.mesh, world, el);
        if (node.camera >= 0) readCamera(node.camera, world, el, node.name);
        if (auto it = node.extensions.find("KHR_lights_punctual"); it != node.extensions.end())
            readGltfPunctualLight(model_, values_, it->second, world, el + ".extensions.KHR_lights_punctual", scene_, warnings_);
        if (auto it = node.extensions.find("TESSERA_sphere"); it != node.extensions.end())
            readSphere(it->second, world, el + ".extensions.TESSERA_sphere");
        if (auto it = node.extensions.find("TESSERA_asset_mesh"); it != node.extensions.end())
            readAssetMesh(it->second, world, el + ".extensions.TESSERA_asset_mesh");
        if (auto it = node.extensions.find("TESSERA_asset_gltf"); it != node.extensions.end())
            readAssetGltf(it->second, world, el + ".extensions.TESSERA_asset_gltf");
        for (int c : node.children) visitNode(c, world, depth + 1);
    }

    /// Records every placed camera; the first in traversal order is the scene's camera and must be
    /// renderable, a later one that is not is kept with its problem (an error only if picked).
    void readCamera(int index, const Mat4d& world, const std::string& nodeEl, const std::string& nodeName) {
        if (index < 0 || size_t(index) >= model_.cameras.size()) fail(nodeEl, "camera index out of range");
        SceneCamera entry{index, model_.cameras[size_t(index)].name, nodeName, std::nullopt, ""};
        try {
            entry.desc = cameraDesc(index, world, nodeEl);
        } catch (const SceneError& e) {
            if (!scene_.camera) throw;
            entry.problem = e.what();
        }
        if (!scene_.camera) scene_.camera = entry.desc;
        scene_.cameras.push_back(std::move(entry));
    }

    CameraDesc cameraDesc(int index, const Mat4d& world, const std::string& nodeEl) const {
        const std::string el = indexedElement("cameras", size_t(index));
        const gl::Camera& cam = model_.cameras[size_t(index)];
        if (cam.type != "perspective") fail(el, "only perspective cameras are supported (got '" + cam.type + "')");
        double yfov = cam.perspective.yfov;
        if (!(yfov > 0.0 && yfov < 3.14159)) fail(el, "yfov must be in (0, pi)");
        CameraDesc d;
        // Remove scale from the camera frame: only position and orientation matter.
        Mat4d m = world;
        for (int c = 0; c < 3; ++c) {
            Vec3d axis(m[c]);
            double len = glm::length(axis);
            if (!(len > 0.0)) fail(nodeEl, "camera transform is singular");
            m[c] = glm::dvec4(axis / len, 0.0);
        }
        d.cameraToWorld = Mat4f(m);
        d.yfov = float(yfov);
        d.znear = cam.perspective.znear > 0.0 ? float(cam.perspective.znear) : 0.01f;
        if (auto it = cam.extensions.find("TESSERA_thin_lens"); it != cam.extensions.end()) {
            const std::string tel = el + ".extensions.TESSERA_thin_lens";
            d.apertureRadius = float(number(it->second, "apertureRadius", tel, 0.0));
            d.focusDistance = float(number(it->second, "focusDistance", tel, 1.0));
            if (d.apertureRadius < 0.f) fail(tel, "apertureRadius must be >= 0");
            if (!(d.focusDistance > 0.f)) fail(tel, "focusDistance must be > 0");
        }
        return d;
    }


    void readSphere(const gl::Value& v, const Mat4d& world, const std::string& el) {
        if (!v.IsObject()) fail(el, "must be an object");
        double radius = number(v, "radius", el, -1.0);
        if (!(radius > 0.0)) fail(el, "'radius' must be a positive number");
        double mat = number(v, "material", el, -1.0);
        uint32_t materialId = defaultMaterial_;
        if (v.Has("material")) {
            if (!(mat >= 0 && mat < double(model_.materials.size())) || mat != std::floor(mat))
                fail(el, "'material' must index materials[]");
            materialId = uint32_t(mat);
        }
        // Spheres stay spheres only under uniform scale.
        double sx = glm::length(Vec3d(world[0])), sy = glm::length(Vec3d(world[1])), sz = glm::length(Vec3d(world[2]));
        if (std::abs(sx - sy) > 1e-6 * sx || std::abs(sx - sz) > 1e-6 * sx)
            fail(el, "a sphere's node transform must scale uniformly");
        Sphere s;
        s.name = el;
        s.center = Vec3f(Vec3d(world[3]));
        s.radius = float(radius * sx);
        s.materialId = materialId;
        if (!(s.radius > 0.f) || !std::isfinite(s.radius) || !isFinite(s.center)) fail(el, "sphere is degenerate after its transform");
        scene_.geometry.spheres.push_back(s);
    }

    /// TESSERA_asset_mesh {asset, material}: a mesh file too large to commit, looked up by name in the
    /// asset folders only (scene/assets.h), so the scene's folder confinement still holds.
    void readAssetMesh(const gl::Value& v, const Mat4d& world, const std::string& el) {
        if (!v.IsObject() || !v.Has("asset") || !v.Get("asset").IsString()) fail(el, "needs an 'asset' name (string)");
        std::string name = v.Get("asset").Get<std::string>();
        uint32_t materialId = defaultMaterial_;
        if (v.Has("material")) {
            double mat = number(v, "material", el, -1.0);
            if (!(mat >= 0 && mat < double(model_.materials.size())) || mat != std::floor(mat))
                fail(el, "'material' must index materials[]");
            materialId = uint32_t(mat);
        }
        // Named by several nodes: read (and its bytes counted) once, then instanced; an emissive
        // one stays flat per node, as lights are world-space triangles.
        const bool instanced = options_.instanceMeshes && assetUses_[name] >= 2 && !scene_.materials[materialId].isEmissive();
        const std::string key = name + "#" + std::to_string(materialId);
        if (instanced)
            if (auto it = assetPrototype_.find(key); it != assetPrototype_.end()) return placeInstance(it->second, world);
        const std::string file = resolveAssetOrThrow(name, options_.assetRoots, options_.maxFileBytes, *assetBytes_, path_, el);
        std::string lower = name;
        for (char& c : lower) c = char(std::tolower(static_cast<unsigned char>(c)));
        auto endsWith = [&](const char* suffix) {
            std::string s(suffix);
            return lower.size() >= s.size() && lower.compare(lower.size() - s.size(), s.size(), s) == 0;
        };
        TriangleMesh mesh;
        if (endsWith(".ply") || endsWith(".ply.gz")) mesh = loadPlyMesh(file);
        else if (endsWith(".obj")) mesh = loadObjMesh(file);
        else fail(el, "asset '" + name + "': only .ply, .ply.gz and .obj meshes are supported");
        mesh.name = name + " (" + el + ")";
        mesh.materialId = materialId;
        mesh.normals.clear();  // flat shading: the loaders' normals (if any) are not transformed here
        const Mat4d placement = instanced ? Mat4d(1.0) : world;  // a prototype stays in object space
        bool flipWinding = glm::determinant(Mat4d(placement)) < 0.0;
        if (!instanced)
            for (Vec3f& p : mesh.positions) p = Vec3f(world * glm::dvec4(Vec3d(p), 1.0));
        std::vector<glm::uvec3> kept;
        kept.reserve(mesh.triangles.size());
        for (glm::uvec3 t : mesh.triangles) {
            if (flipWinding) std::swap(t.y, t.z);
            if (!keepTriangle(mesh, t)) continue;
            kept.push_back(t);
        }
        if (kept.empty()) fail(el, "asset '" + name + "' has no usable triangles");
        mesh.triangles = std::move(kept);
        if (instanced) {
            std::vector<TriangleMesh> objectSpace;
            objectSpace.push_back(std::move(mesh));
            uint32_t prototype = addPrototype(std::move(objectSpace));
            assetPrototype_[key] = prototype;
            placeInstance(prototype, world);
            return;
        }
        scene_.geometry.meshes.push_back(std::move(mesh));
    }

    /// TESSERA_asset_gltf {asset}: a glTF/GLB file from the asset folders, loaded by a Loader of its
    /// own (same options; its URIs confined to its folder) whose root transform is this node's, and
    /// merged (scene/gltf_asset.h). Its errors are reported as this element's, with the asset's own
    /// "FILE: ELEMENT: PROBLEM" after it.
    void readAssetGltf(const gl::Value& v, const Mat4d& world, const std::string& el) {
        if (!v.IsObject() || !v.Has("asset") || !v.Get("asset").IsString()) fail(el, "needs an 'asset' name (string)");
        const std::string name = v.Get("asset").Get<std::string>();
        const std::string file = resolveAssetOrThrow(name, options_.assetRoots, options_.maxFileBytes, *assetBytes_, path_, el);
        std::string lower = name;
        for (char& c : lower) c = char(std::tolower(static_cast<unsigned char>(c)));
        if (!lower.ends_with(".glb") && !lower.ends_with(".gltf")) fail(el, "asset '" + name + "': only .glb and .gltf files are supported");
        if (nesting_ >= kMaxAssetNesting)
            fail(el, "assets nested deeper than " + std::to_string(kMaxAssetNesting) + " (does an asset name itself?)");
        Scene asset;
        try {
            asset = Loader(file, warnings_, options_, world, nesting_ + 1, assetBytes_).loadUnfinalized();
        } catch (const SceneError& e) {
            fail(el, "asset '" + name + "': " + e.what());
        }
        appendAssetScene(scene_, std::move(asset));
    }

    /// Byte view of accessor `a` after checking type, bounds and layout.
    struct View {
        const unsigned char* data = nullptr;
        size_t stride = 0, count = 0;
    };
    View accessorView(int accessorIndex, const std::string& el, int type, std::initializer_list<int> componentTypes) const {
        if (accessorIndex < 0 || size_t(accessorIndex) >= model_.accessors.size()) fail(el, "accessor index out of range");
        const gl::Accessor& a = model_.accessors[size_t(accessorIndex)];
        const std::string ael = indexedElement("accessors", size_t(accessorIndex));
        if (a.sparse.isSparse) fail(ael, "sparse accessors are not supported");
        if (a.type != type) fail(ael, "unexpected accessor type for " + el);
        if (std::find(componentTypes.begin(), componentTypes.end(), a.componentType) == componentTypes.end())
            fail(ael, "unexpected component type " + std::to_string(a.componentType) + " for " + el);
        if (a.bufferView < 0 || size_t(a.bufferView) >= model_.bufferViews.size()) fail(ael, "bufferView index out of range");
        const gl::BufferView& bv = model_.bufferViews[size_t(a.bufferView)];
        const std::string bel = indexedElement("bufferViews", size_t(a.bufferView));
        if (bv.buffer < 0 || size_t(bv.buffer) >= model_.buffers.size()) fail(bel, "buffer index out of range");
        const gl::Buffer& buf = model_.buffers[size_t(bv.buffer)];
        size_t elemSize = size_t(gl::GetComponentSizeInBytes(uint32_t(a.componentType))) *
                          size_t(gl::GetNumComponentsInType(uint32_t(a.type)));
        size_t stride = bv.byteStride > 0 ? bv.byteStride : elemSize;
        if (stride < elemSize) fail(bel, "byteStride smaller than the element size");
        if (bv.byteOffset > buf.data.size() || bv.byteLength > buf.data.size() - bv.byteOffset)
            fail(bel, "view exceeds its buffer (" + std::to_string(buf.data.size()) + " bytes)");
        if (a.count > 0) {
            // 128-bit arithmetic is unnecessary: count and stride are bounded by the buffer size
            // check below, done in an order that cannot overflow.
            if (a.byteOffset > bv.byteLength) fail(ael, "byteOffset beyond its bufferView");
            size_t avail = bv.byteLength - a.byteOffset;
            if (avail < elemSize || (a.count - 1) > (avail - elemSize) / stride)
                fail(ael, "accessor of " + std::to_string(a.count) + " elements exceeds its bufferView");
        }
        return View{buf.data.data() + bv.byteOffset + a.byteOffset, stride, a.count};
    }

    /// A VEC3 attribute (POSITION, NORMAL) as floats: FLOAT, or the integer types KHR_mesh_quantization
    /// allows (BYTE, UNSIGNED_BYTE, SHORT, UNSIGNED_SHORT, normalized or not), whose scale and offset
    /// the node transforms carry.
    std::vector<Vec3f> readVec3(int accessor, const std::string& el) const {
        View v = accessorView(accessor, el, TINYGLTF_TYPE_VEC3, kFloatOrQuantized);
        const gl::Accessor& a = model_.accessors[size_t(accessor)];
        std::vector<Vec3f> out(v.count);
        if (a.componentType == TINYGLTF_COMPONENT_TYPE_FLOAT) {
            for (size_t i = 0; i < v.count; ++i) std::memcpy(&out[i], v.data + i * v.stride, sizeof(Vec3f));
            return out;
        }
        const size_t size = size_t(gl::GetComponentSizeInBytes(uint32_t(a.componentType)));
        for (size_t i = 0; i < v.count; ++i)
            for (int c = 0; c < 3; ++c)
                out[i][c] = componentAsFloat(v.data + i * v.stride + size_t(c) * size, a.componentType, a.normalized);
        return out;
    }

    std::vector<uint32_t> readIndices(int accessor, const std::string& el) const {
        View v = accessorView(accessor, el, TINYGLTF_TYPE_SCALAR,
                              {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                               TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT});
        int ct = model_.accessors[size_t(accessor)].componentType;
        std::vector<uint32_t> out(v.count);
        for (size_t i = 0; i < v.count; ++i) {
            const unsigned char* p = v.data + i * v.stride;
            if (ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE) out[i] = *p;
            else if (ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT) { uint16_t s; std::memcpy(&s, p, 2); out[i] = s; }
            else std::memcpy(&out[i], p, 4);
        }
        return out;
    }

    /// How many nodes name each mesh and each TESSERA_asset_mesh asset: what is named twice or more
    /// is instanced (when options_.instanceMeshes).
    void countReferences() {
        meshUses_.assign(model_.meshes.size(), 0);
        for (const gl::Node& n : model_.nodes) {
            if (n.mesh >= 0 && size_t(n.mesh) < meshUses_.size()) ++meshUses_[size_t(n.mesh)];
            auto it = n.extensions.find("TESSERA_asset_mesh");
            if (it != n.extensions.end() && it->second.IsObject() && it->second.Has("asset") && it->second.Get("asset").IsString())
                ++assetUses_[it->second.Get("asset").Get<std::string>()];
        }
    }

    /// A new prototype holding `meshes` (object space); kInvalidId when there are none.
    uint32_t addPrototype(std::vector<TriangleMesh>&& meshes) {
        if (meshes.empty()) return kInvalidId;
        SceneGeometry proto;
        proto.meshes = std::move(meshes);
        scene_.geometry.prototypes.push_back(std::move(proto));
        return uint32_t(scene_.geometry.prototypes.size() - 1);
    }

    /// An instance of `prototype` at `world`; a singular transform places nothing (its triangles
    /// count as dropped degenerate ones, as a flattened copy's would be).
    void placeInstance(uint32_t prototype, const Mat4d& world) {
        if (prototype == kInvalidId) return;
        MeshInstance inst;
        if (makeMeshInstance(prototype, world, inst)) scene_.geometry.instances.push_back(inst);
        else droppedTriangles_ += scene_.geometry.prototypes[prototype].primitiveCount();
    }

    /// Mesh `meshIndex` placed at `world`. Named by one node (or with instancing off): its primitives
    /// in world space, as flat meshes. Named by several: its primitives are read once in object
    /// space into a prototype that each node instances, except emissive ones, which stay flat per
    /// node so that lights remain world-space triangles (scene/lights.h).
    void readMesh(int meshIndex, const Mat4d& world, const std::string& nodeEl) {
        if (size_t(meshIndex) >= model_.meshes.size()) fail(nodeEl, "mesh index out of range");
        if (!options_.instanceMeshes || meshUses_[size_t(meshIndex)] < 2) {
            readPrimitives(meshIndex, world, Primitives::kAll, scene_.geometry.meshes);
            return;
        }
        auto [it, fresh] = meshPrototype_.try_emplace(meshIndex, kInvalidId);
        if (fresh) {
            std::vector<TriangleMesh> objectSpace;
            readPrimitives(meshIndex, Mat4d(1.0), Primitives::kNonEmissive, objectSpace);
            it->second = addPrototype(std::move(objectSpace));
        }
        placeInstance(it->second, world);
        readPrimitives(meshIndex, world, Primitives::kEmissive, scene_.geometry.meshes);
    }

    enum class Primitives { kAll, kNonEmissive, kEmissive };

    /// The triangle primitives of mesh `meshIndex` that `which` selects, transformed by `world`,
    /// appended to `out`.
    void readPrimitives(int meshIndex, const Mat4d& world, Primitives which, std::vector<TriangleMesh>& out) {
        const gl::Mesh& gm = model_.meshes[size_t(meshIndex)];
        // A mirroring transform reverses the winding (glTF 2.0 spec, 3.7.4): flip it back so front
        // faces, and so one-sided emitters, keep facing the way the artist meant (pbrt-v3 #229).
        bool flipWinding = glm::determinant(Mat4d(world)) < 0.0;
        Mat4d normalMatrix = glm::transpose(glm::inverse(world));
        for (size_t p = 0; p < gm.primitives.size(); ++p) {
            const gl::Primitive& prim = gm.primitives[p];
            const std::string el = indexedElement("meshes", size_t(meshIndex)) + "." + indexedElement("primitives", p);
            int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
            if (mode == TINYGLTF_MODE_POINTS || mode == TINYGLTF_MODE_LINE || mode == TINYGLTF_MODE_LINE_LOOP ||
                mode == TINYGLTF_MODE_LINE_STRIP) {
                warnings_.push_back(path_ + ": " + el + ": points and lines are not rendered");
                continue;
            }
            if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP && mode != TINYGLTF_MODE_TRIANGLE_FAN)
                fail(el, "unknown primitive mode " + std::to_string(mode));
            auto pos = prim.attributes.find("POSITION");
            if (pos == prim.attributes.end()) fail(el, "has no POSITION attribute");
            TriangleMesh mesh;
            mesh.name = gm.name.empty() ? el : gm.name + " (" + el + ")";
            mesh.positions = readVec3(pos->second, el + ".attributes.POSITION");
            if (auto nrm = prim.attributes.find("NORMAL"); nrm != prim.attributes.end()) {
                mesh.normals = readVec3(nrm->second, el + ".attributes.NORMAL");
                if (mesh.normals.size() != mesh.positions.size()) fail(el, "NORMAL and POSITION counts differ");
            }
            std::vector<uint32_t> indices;
            if (prim.indices >= 0) {
                indices = readIndices(prim.indices, el + ".indices");
            } else {
                indices.resize(mesh.positions.size());
                for (size_t i = 0; i < indices.size(); ++i) indices[i] = uint32_t(i);
            }
            for (uint32_t i : indices)
                if (i >= mesh.positions.size())
                    fail(el, "index " + std::to_string(i) + " out of range (" + std::to_string(mesh.positions.size()) + " vertices)");
            if (prim.material >= 0 && size_t(prim.material) >= model_.materials.size()) fail(el, "material index out of range");
            mesh.materialId = prim.material >= 0 ? uint32_t(prim.material) : defaultMaterial_;
            bool emissive = scene_.materials[mesh.materialId].isEmissive();
            if ((which == Primitives::kNonEmissive && emissive) || (which == Primitives::kEmissive && !emissive)) continue;
            mesh.triangles = assembleTriangles(indices, mode, el);
            readTextureAttributes(prim, mesh, el);
            std::vector<glm::uvec3> tris = std::move(mesh.triangles);
            mesh.triangles.clear();

            for (Vec3f& v : mesh.positions) v = Vec3f(world * glm::dvec4(Vec3d(v), 1.0));
            for (Vec3f& n : mesh.normals) {
                Vec3f t = Vec3f(Mat4d(normalMatrix) * glm::dvec4(Vec3d(n), 0.0));
                float len = glm::length(t);
                n = len > 0.f && std::isfinite(len) ? t / len : Vec3f(0.f);
            }
            // Tangents lie in the surface: they transform like positions (without translation), and
            // a mirroring transform flips the bitangent sign (B = w · N × T with N, T both mapped).
            for (Vec4f& t : mesh.tangents) {
                Vec3f d = Vec3f(world * glm::dvec4(Vec3d(Vec3f(t)), 0.0));
                float len = glm::length(d);
                t = Vec4f(len > 0.f && std::isfinite(len) ? d / len : Vec3f(0.f), flipWinding ? -t.w : t.w);
            }
            mesh.alphaMask = alphaMasks_[mesh.materialId];
            mesh.triangles.reserve(tris.size());
            for (glm::uvec3 t : tris) {
                if (flipWinding) std::swap(t.y, t.z);
                if (!keepTriangle(mesh, t)) continue;
                mesh.triangles.push_back(t);
            }
            if (mesh.triangles.empty() && !tris.empty()) {
                if (scene_.materials[mesh.materialId].isEmissive()) fail(el, "emitter has zero area");
                fail(el, "all " + std::to_string(tris.size()) + " triangle(s) are degenerate or have non-finite vertices");
            }
            out.push_back(std::move(mesh));
        }
    }

    /// TEXCOORD_0/_1 and TANGENT (object space), checked against what the material samples;
    /// MikkTSpace tangents when a normal texture has none from the file (glTF 2.0, 3.7.2.1).
    void readTextureAttributes(const gl::Primitive& prim, TriangleMesh& mesh, const std::string& el) {
        const size_t n = mesh.positions.size();
        for (int set = 0; set < 2; ++set) {
            const std::string name = "TEXCOORD_" + std::to_string(set);
            auto it = prim.attributes.find(name);
            if (it == prim.attributes.end()) continue;
            std::vector<float> f = readFloats(it->second, el + ".attributes." + name, TINYGLTF_TYPE_VEC2, 2);
            if (f.size() != 2 * n) fail(el, name + " and POSITION counts differ");
            mesh.texcoords[set].resize(n);
            for (size_t i = 0; i < n; ++i) mesh.texcoords[set][i] = Vec2f(f[2 * i], f[2 * i + 1]);
        }
        const Material& m = scene_.materials[mesh.materialId];
        const MaterialTextures& t = m.textures;
        for (const TextureRef* ref : {&t.baseColor, &t.metallicRoughness, &t.normal, &t.emissive, &t.transmission, &t.specular, &t.specularColor})
            if (ref->valid() && !mesh.hasTexcoords(ref->texCoord))
                fail(el, "material '" + m.name + "' samples TEXCOORD_" + std::to_string(ref->texCoord) + ", which the primitive lacks");
        if (!t.normal.valid()) return;  // tangents only serve normal mapping
        auto it = prim.attributes.find("TANGENT");
        // Without NORMAL the surface is flat shaded and a file's tangents are ignored (3.7.2.1).
        if (it != prim.attributes.end() && !mesh.normals.empty()) {
            std::vector<float> f = readFloats(it->second, el + ".attributes.TANGENT", TINYGLTF_TYPE_VEC4, 4);
            if (f.size() != 4 * n) fail(el, "TANGENT and POSITION counts differ");
            mesh.tangents.resize(n);
            for (size_t i = 0; i < n; ++i) mesh.tangents[i] = Vec4f(f[4 * i], f[4 * i + 1], f[4 * i + 2], f[4 * i + 3] < 0.f ? -1.f : 1.f);
            return;
        }
        if (mesh.normals.empty()) unweldWithFlatNormals(mesh);
        generateMikkTangents(mesh, t.normal.texCoord);
    }

    /// Components of an attribute as floats: FLOAT, or the integer types normalized to [0, 1] /
    /// [−1, 1] as glTF 2.0 (3.11) defines, or taken as integers when not normalized
    /// (KHR_mesh_quantization), through componentAsFloat.
    std::vector<float> readFloats(int accessor, const std::string& el, int type, int components) const {
        View v = accessorView(accessor, el, type, kFloatOrQuantized);
        const gl::Accessor& a = model_.accessors[size_t(accessor)];
        const size_t size = size_t(gl::GetComponentSizeInBytes(uint32_t(a.componentType)));
        std::vector<float> out(v.count * size_t(components));
        for (size_t i = 0; i < v.count; ++i)
            for (int c = 0; c < components; ++c) {
                float f = componentAsFloat(v.data + i * v.stride + size_t(c) * size, a.componentType, a.normalized);
                out[i * size_t(components) + size_t(c)] = std::isfinite(f) ? f : 0.f;  // a NaN uv or tangent must not reach a lookup
            }
        return out;
    }

    std::vector<glm::uvec3> assembleTriangles(const std::vector<uint32_t>& ix, int mode, const std::string& el) const {
        std::vector<glm::uvec3> tris;
        if (mode == TINYGLTF_MODE_TRIANGLES) {
            if (ix.size() % 3 != 0) fail(el, "triangle index count " + std::to_string(ix.size()) + " is not a multiple of 3");
            for (size_t i = 0; i < ix.size(); i += 3) tris.emplace_back(ix[i], ix[i + 1], ix[i + 2]);
        } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
            for (size_t i = 2; i < ix.size(); ++i)
                tris.push_back(i % 2 == 0 ? glm::uvec3(ix[i - 2], ix[i - 1], ix[i]) : glm::uvec3(ix[i - 1], ix[i - 2], ix[i]));
        } else {  // fan
            for (size_t i = 2; i < ix.size(); ++i) tris.emplace_back(ix[0], ix[i - 1], ix[i]);
        }
        return tris;
    }

    std::string path_;
    std::vector<std::string>& warnings_;
    SceneLoadOptions options_;
    Mat4d root_;
    int nesting_ = 0;
    uint64_t ownAssetBytes_ = 0;
    uint64_t* assetBytes_;  ///< bytes of asset files read by the whole scene load (nested loaders share it)
    GltfValues values_{path_};
    GltfFileAccess access_;
    gl::Model model_;
    std::vector<std::shared_ptr<const AlphaMask>> alphaMasks_;  ///< per material (null: opaque)
    Scene scene_;
    uint32_t defaultMaterial_ = 0;
    std::set<int> visited_;
    std::vector<int> meshUses_;                    ///< nodes naming each mesh
    std::map<std::string, int> assetUses_;         ///< nodes naming each TESSERA_asset_mesh asset
    std::map<int, uint32_t> meshPrototype_;        ///< instanced mesh → its prototype (kInvalidId: none)
    std::map<std::string, uint32_t> assetPrototype_;  ///< "asset#material" → its prototype
    size_t droppedTriangles_ = 0;

    /// False (and counted in the warning) for a triangle of zero area or with a non-finite vertex or
    /// normal: no structure or light may see one.
    bool keepTriangle(const TriangleMesh& mesh, glm::uvec3 t) {
        const Vec3f &a = mesh.positions[t.x], &b = mesh.positions[t.y], &c = mesh.positions[t.z];
        Vec3f n = glm::cross(b - a, c - a);
        if (isFinite(a) && isFinite(b) && isFinite(c) && glm::dot(n, n) > 0.f && isFinite(n)) return true;
        ++droppedTriangles_;
        return false;
    }
};

}  // namespace

std::vector<std::string> supportedGltfExtensions() {
    return {"KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_materials_transmission", "KHR_materials_ior",
            "KHR_materials_specular", "KHR_materials_volume", "KHR_texture_transform",
            "KHR_mesh_quantization",
            "TESSERA_render", "TESSERA_sphere", "TESSERA_thin_lens", "TESSERA_asset_mesh", "TESSERA_asset_gltf",
            "TESSERA_environment"};
}

Scene loadGltfScene(const std::string& path, std::vector<std::string>& warnings) {
    return Loader(path, warnings, SceneLoadOptions{}).load();
}

Scene loadGltfScene(const std::string& path, std::vector<std::string>& warnings, const SceneLoadOptions& options) {
    return Loader(path, warnings, options).load();
}

}  // namespace tessera
