/// \file validate_accel_command.cpp
/// `tessera validate-accel INPUT`: casts the same rays through an acceleration structure and through
/// Embree and reports agreements, admissible ties and errors. Exit code 1 when there is an error.
#include <nlohmann/json.hpp>

#include <chrono>
#include <iostream>

#include "validation/instanced_scenes.h"
#include "validation/validate.h"
#include "app/commands.h"
#include "scene/scene_loader.h"

namespace tessera::app {

Runner addValidateAccelCommand(CLI::App& app) {
    struct Options {
        std::string input, accel = "bvh", kind = "all";
        size_t rays = 1000000;
        uint64_t seed = 1;
        bool json = false;
    };
    auto opt = std::make_shared<Options>();
    CLI::App* cmd = app.add_subcommand("validate-accel", "Compare an acceleration structure with Embree, ray by ray");
    cmd->add_option("INPUT", opt->input, "glTF scene, PLY (also .ply.gz) or OBJ mesh")->required();
    cmd->add_option("--accel", opt->accel, "structure to check")->capture_default_str();
    cmd->add_option("--rays", opt->rays, "number of rays (split evenly over the kinds with --kind all)")->capture_default_str();
    cmd->add_option("--kind", opt->kind, "primary, random, diffuse, grazing or all")->capture_default_str();
    cmd->add_option("--seed", opt->seed, "seed of the ray generator")->capture_default_str();
    cmd->add_flag("--json", opt->json, "print one JSON object instead of text");
    cmd->footer("Same primitive: t within 1e-5 relative, u, v within 1e-4, normals within 1e-4 (cosine).\n"
                "A tie is a ray whose answers differ admissibly (confirmed in double precision): two primitives\n"
                "hit at the same t (shared edge, duplicates), or a ray grazing an edge or a silhouette.\n"
                "Cut-out meshes (alphaMode MASK): a hit inside a hole is an error, one within rounding of the\n"
                "mask's cutoff contour a tie; Embree drops cut-out hits in its filter functions.");
    return [opt] {
        std::vector<std::string> warnings;
        std::optional<CameraDesc> camera;
        SceneGeometry geometry = loadGeometryFile(opt->input, camera, warnings);
        size_t maskedMeshes = 0;
        for (const TriangleMesh& m : geometry.meshes) maskedMeshes += m.alphaMask != nullptr;
        std::vector<RayKind> kinds;
        if (opt->kind == "all") kinds.assign(std::begin(kValidationRayKinds), std::end(kValidationRayKinds));
        else kinds.push_back(parseRayKind(opt->kind));

        auto test = createAccel(opt->accel, geometry);
        auto reference = createAccel("embree", geometry);
        // Instanced scenes: records are compared in the flattened copy's numbering (instanced_scenes.h),
        // against Embree's instanced scene and against Embree over the flattened copy.
        const bool instanced = !geometry.instances.empty();
        InstanceFlattening flattening(geometry);
        SceneGeometry flat = instanced ? flattening.flatten() : SceneGeometry{};
        const SceneGeometry& compared = instanced ? flat : geometry;
        std::unique_ptr<Accel> flatReference = instanced ? createAccel("embree", flat) : nullptr;
        FlattenedIds testIds(*test, flattening), referenceIds(*reference, flattening);
        const Accel& testSeen = instanced ? static_cast<const Accel&>(testIds) : *test;
        const Accel& referenceSeen = instanced ? static_cast<const Accel&>(referenceIds) : *reference;
        ValidationResult total, totalFlat;
        nlohmann::json perKind = nlohmann::json::object();
        auto start = std::chrono::steady_clock::now();
        for (size_t k = 0; k < kinds.size(); ++k) {
            size_t n = opt->rays / kinds.size() + (k < opt->rays % kinds.size() ? 1 : 0);
            std::vector<Ray> rays = generateRays(compared, referenceSeen, kinds[k], n, opt->seed, camera);
            ValidationResult r = compareAccels(testSeen, referenceSeen, compared, rays, kinds[k]);
            perKind[std::string(toString(kinds[k]))] = {{"rays", r.rays}, {"agreements", r.agreements}, {"ties", r.ties}, {"errors", r.errors}};
            total.merge(r, 20);
            if (instanced) {
                ValidationResult f = compareAccels(testSeen, *flatReference, compared, rays, kinds[k]);
                perKind[std::string(toString(kinds[k])) + " (vs flattened)"] = {
                    {"rays", f.rays}, {"agreements", f.agreements}, {"ties", f.ties}, {"errors", f.errors}};
                totalFlat.merge(f, 20);
            }
        }
        if (instanced && !opt->json) {
            std::cout << "instanced scene: " << geometry.instances.size() << " instances of " << geometry.prototypes.size()
                      << " prototype(s); compared against embree (instanced) and embree over the flattened copy ("
                      << flat.primitiveCount() << " primitives): " << totalFlat.errors << " errors against the flattened copy\n";
        }
        if (instanced) {
            total.errors += totalFlat.errors;
            for (const ValidationExample& e : totalFlat.examples)
                if (total.examples.size() < 20) total.examples.push_back(e);
        }
        double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (opt->json) {
            nlohmann::json j = toJson(total);
            j["input"] = opt->input;
            j["accel"] = opt->accel;
            j["reference"] = "embree";
            j["primitives"] = geometry.primitiveCount() + geometry.instancedPrimitiveCount();
            j["alpha_masked_meshes"] = maskedMeshes;
            j["seed"] = opt->seed;
            j["kinds"] = perKind;
            j["instances"] = geometry.instances.size();
            j["errors_vs_flattened"] = totalFlat.errors;
            j["seconds"] = seconds;
            std::cout << j.dump(2) << std::endl;
        } else {
            std::cout << opt->accel << " vs embree on " << opt->input << " (" << geometry.primitiveCount() + geometry.instancedPrimitiveCount()
                      << " primitives, " << maskedMeshes << " alpha-masked meshes, seed " << opt->seed << ")\n";
            for (auto& [name, v] : perKind.items())
                std::cout << "  " << name << ": " << v["rays"] << " rays, " << v["agreements"] << " agree, " << v["ties"]
                          << " ties, " << v["errors"] << " errors\n";
            std::cout << "total: " << total.rays << " rays, " << total.agreements << " agree, " << total.ties
                      << " ties, " << total.errors << " errors (" << seconds << " s)\n";
            for (const ValidationExample& e : total.examples)
                std::cout << "  error [" << toString(e.kind) << " #" << e.rayIndex << "] " << e.reason << ": ray "
                          << toJson(e.ray).dump() << " test " << toJson(e.test, e.testHit).dump() << " reference "
                          << toJson(e.ref, e.refHit).dump() << "\n";
        }
        for (const std::string& w : warnings) printWarning(w);
        return total.errors > 0 ? 1 : 0;
    };
}

}  // namespace tessera::app
