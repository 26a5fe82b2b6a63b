#include "scene/gltf_lights.h"

#include <filesystem>

#include "core/error.h"
#include "scene/environment.h"
#include "scene/gltf_asset.h"
#include "scene/gltf_files.h"

namespace tessera {

namespace gl = tinygltf;

void GltfValues::fail(const std::string& element, const std::string& problem) const { throw SceneError(path, element, problem); }

/// An optional RGB array member with components in [0, maxComponent].
Rgb GltfValues::color3(const gl::Value& obj, const char* key, const std::string& element, Rgb fallback, double maxComponent) const {
    if (!obj.IsObject() || !obj.Has(key)) return fallback;
    const gl::Value& a = obj.Get(key);
    if (!a.IsArray() || a.ArrayLen() != 3) fail(element, std::string(key) + " must be an array of 3 numbers");
    Rgb c;
    for (int i = 0; i < 3; ++i) {
        const gl::Value& x = a.Get(i);
        double d = x.IsNumber() ? x.GetNumberAsDouble() : -1.0;
        if (!(d >= 0.0 && d <= maxComponent)) fail(element, std::string(key) + " components must be in [0, " + (maxComponent > 1e29 ? "inf" : "1") + ")");
        c[i] = float(d);
    }
    return c;
}

double GltfValues::number(const gl::Value& obj, const char* key, const std::string& element, double fallback) const {
    if (!obj.Has(key)) return fallback;
    const gl::Value& v = obj.Get(key);
    if (!v.IsNumber()) fail(element, std::string("'") + key + "' must be a number");
    double d = v.GetNumberAsDouble();
    if (!std::isfinite(d)) fail(element, std::string("'") + key + "' must be finite");
    return d;
}

/// KHR_lights_punctual point, spot and directional lights. glTF gives point and spot intensities
/// in candela (lm/sr), directional ones in lux (lm/m²), and emission in nits (cd/m²); Tessera
/// reads emissive values as radiance 1:1, so for the same scale it reads candela as radiant
/// intensity (W/sr) and lux as irradiance (W/m²) 1:1: I = intensity · color, E = intensity ·
/// color. Spot and directional lights shine along the node's local −Z. `range` is ignored
/// (physically based inverse-square falloff, as the extension recommends).
void readGltfPunctualLight(const gl::Model& model, const GltfValues& values, const gl::Value& v, const Mat4d& world,
                           const std::string& el, Scene& scene, std::vector<std::string>& warnings) {
    if (!v.IsObject() || !v.Has("light") || !v.Get("light").IsNumber()) values.fail(el, "needs a 'light' index");
    double index = v.Get("light").GetNumberAsDouble();
    if (!(index >= 0 && index < double(model.lights.size())) || index != std::floor(index))
        values.fail(el, "'light' must index extensions.KHR_lights_punctual.lights[]");
    const gl::Light& gl = model.lights[size_t(index)];
    const std::string lel = indexedElement("KHR_lights_punctual.lights", size_t(index));
    if (gl.type != "point" && gl.type != "spot" && gl.type != "directional") {
        warnings.push_back(values.path + ": " + lel + ": light type '" + gl.type + "' is not supported and is ignored");
        return;
    }
    if (!(gl.intensity >= 0.0) || !std::isfinite(gl.intensity)) values.fail(lel, "intensity must be finite and non-negative");
    Rgb color(1.f);
    if (!gl.color.empty()) {
        if (gl.color.size() != 3) values.fail(lel, "color must have 3 components");
        for (int c = 0; c < 3; ++c) {
            if (!(gl.color[size_t(c)] >= 0.0 && gl.color[size_t(c)] <= 1.0)) values.fail(lel, "color components must be in [0, 1]");
            color[c] = float(gl.color[size_t(c)]);
        }
    }
    Rgb value = color * float(gl.intensity);
    if (isBlack(value)) return;
    Vec3f position = Vec3f(Vec3d(world[3]));
    if (!isFinite(position)) values.fail(el, "light position is not finite");
    Vec3d axis = -Vec3d(world[2]);  // the node's −Z in world space
    double axisLength = glm::length(axis);
    if (gl.type != "point" && !(axisLength > 0.0 && std::isfinite(axisLength))) values.fail(el, "light direction is degenerate");
    Vec3f direction = Vec3f(axis / axisLength);
    if (gl.type == "point") {
        scene.pointLights.push_back(PointLightDesc{position, value});
    } else if (gl.type == "spot") {
        double inner = gl.spot.innerConeAngle, outer = gl.spot.outerConeAngle;
        // The extension: 0 ≤ innerConeAngle < outerConeAngle ≤ π/2.
        if (!(inner >= 0.0 && inner < outer && outer <= 0.5 * kPi + 1e-6))
            values.fail(lel, "spot cone angles must satisfy 0 <= innerConeAngle < outerConeAngle <= pi/2");
        scene.spotLights.push_back(SpotLightDesc{position, direction, value, float(inner), float(std::min(outer, 0.5 * kPi))});
    } else {
        scene.directionalLights.push_back(DirectionalLightDesc{direction, value});
    }
}

/// TESSERA_environment at the glTF root: {"color": [r, g, b], "intensity": s, "rotation": degrees,
/// and optionally "image": "file.exr" (a relative URI, confined to the scene's folder like
/// buffers) or "asset": "name" (looked up in the asset folders like TESSERA_asset_mesh)}. The
/// radiance is color × intensity (× the image, linear, equirectangular: scene/environment.h).
void readGltfEnvironment(const gl::Model& model, const GltfValues& values, const SceneLoadOptions& options, uint64_t& assetBytes,
                         Scene& scene) {
    auto it = model.extensions.find("TESSERA_environment");
    if (it == model.extensions.end()) return;
    const gl::Value& v = it->second;
    const std::string el = "extensions.TESSERA_environment";
    if (!v.IsObject()) values.fail(el, "must be an object");
    EnvironmentDesc env;
    env.color = values.color3(v, "color", el, Rgb(1.f), 1e30);
    double intensity = values.number(v, "intensity", el, 1.0);
    if (!(intensity >= 0.0 && intensity <= 1e30)) values.fail(el, "'intensity' must be a non-negative number");
    env.intensity = float(intensity);
    env.rotationDeg = float(values.number(v, "rotation", el, 0.0));
    env.source = "constant";
    if (v.Has("image") && v.Has("asset")) values.fail(el, "give either 'image' or 'asset', not both");
    std::string file;
    if (v.Has("image")) {
        if (!v.Get("image").IsString()) values.fail(el, "'image' must be a string (a file relative to the scene)");
        std::string uri = v.Get("image").Get<std::string>();
        std::error_code ec;
        std::filesystem::path folder = std::filesystem::weakly_canonical(std::filesystem::absolute(values.path), ec).parent_path();
        file = (folder / uri).string();
        GltfFileAccess access;  // the confinement buffers and images have (scene/gltf_files.h)
        access.root = folder;
        access.options = options;
        if (!access.allowed(file)) values.fail(el, access.violation.empty() ? "cannot resolve '" + uri + "'" : access.violation);
        if (!std::filesystem::is_regular_file(file, ec)) values.fail(el, "image '" + uri + "' not found");
        uint64_t size = std::filesystem::file_size(file, ec);
        if (ec || size > options.maxFileBytes) values.fail(el, "'" + uri + "' is unreadable or over the file-size limit");
    } else if (v.Has("asset")) {
        if (!v.Get("asset").IsString()) values.fail(el, "'asset' must be a string");
        std::string name = v.Get("asset").Get<std::string>();
        // The one asset resolution (name rules, folders, the scene's running byte total).
        file = resolveAssetOrThrow(name, options.assetRoots, options.maxFileBytes, assetBytes, values.path, el);
        env.source = "asset " + name;
    }
    if (!file.empty()) {
        std::unique_ptr<Image> image;
        try {
            image = readEnvironmentImage(file);
        } catch (const InputError& e) {
            values.fail(el, e.what());
        }
        scene.images.push_back(std::move(image));
        env.image = scene.images.back().get();
        if (env.source == "constant") env.source = v.Get("image").Get<std::string>();  // as the scene names it
    }
    scene.environment = env;
}

}  // namespace tessera
