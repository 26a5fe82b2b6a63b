// What a user of the installed library writes: build geometry, wrap their own intersection routine,
// and check it hit for hit against Embree with tessera::api::validate. Here the "user's" routine
// is a plain Möller–Trumbore brute force (Möller & Trumbore 1997) written only against the public
// header, plus a deliberately broken variant that validation must catch.
// Usage: consumer SCENE [PATHOLOGY.obj ...]  (SCENE a glTF/PLY/OBJ file, the test passes the Cornell
// box; then meshes of the pathology battery, the test passes the integer lattice and the hairball)
#include <tessera/tessera.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace api = tessera::api;

namespace {

struct V3 {
    double x, y, z;
};
V3 sub(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V3 cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

/// The user's own reading of a plain OBJ file (v and f lines, 1-based, triangles).
void readObj(const std::string& path, std::vector<float>& p, std::vector<uint32_t>& idx) {
    std::ifstream in(path);
    if (!in) throw std::runtime_error("cannot read " + path);
    std::string line;
    while (std::getline(in, line)) {
        std::istringstream ss(line);
        std::string tag;
        ss >> tag;
        if (tag == "v") {
            float x, y, z;
            ss >> x >> y >> z;
            p.insert(p.end(), {x, y, z});
        } else if (tag == "f") {
            uint32_t a, b, c;
            ss >> a >> b >> c;
            idx.insert(idx.end(), {a - 1, b - 1, c - 1});
        }
    }
}

/// The user's intersector: double-precision Möller–Trumbore over every triangle.
bool bruteForce(const std::vector<V3>& verts, const std::vector<uint32_t>& idx, const api::Ray& r, api::Hit& hit) {
    V3 o{r.origin[0], r.origin[1], r.origin[2]}, d{r.direction[0], r.direction[1], r.direction[2]};
    bool found = false;
    double best = r.tMax;
    for (size_t t = 0; t < idx.size() / 3; ++t) {
        V3 p0 = verts[idx[3 * t]], p1 = verts[idx[3 * t + 1]], p2 = verts[idx[3 * t + 2]];
        V3 e1 = sub(p1, p0), e2 = sub(p2, p0), pv = cross(d, e2);
        double det = dot(e1, pv);
        if (det == 0.0) continue;
        V3 tv = sub(o, p0);
        double u = dot(tv, pv) / det;
        V3 qv = cross(tv, e1);
        double v = dot(d, qv) / det, tt = dot(e2, qv) / det;
        if (u < 0 || v < 0 || u + v > 1 || !(tt > r.tMin) || !(tt < best)) continue;
        V3 n = cross(e1, e2);
        double len = std::sqrt(dot(n, n));
        best = tt;
        hit = {float(tt), float(u), float(v), uint32_t(t), 0, {float(n.x / len), float(n.y / len), float(n.z / len)}};
        found = true;
    }
    return found;
}

std::vector<V3> toV3(const std::vector<float>& p) {
    std::vector<V3> verts;
    for (size_t i = 0; i < p.size(); i += 3) verts.push_back({p[i], p[i + 1], p[i + 2]});
    return verts;
}

int failures = 0;
void check(bool ok, const char* what) {
    std::printf("%s: %s\n", ok ? "ok  " : "FAIL", what);
    if (!ok) ++failures;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: consumer SCENE [PATHOLOGY.obj ...]\n");
        return 2;
    }
    try {
        std::printf("tessera %s\n", api::version().c_str());

        // 1. A user-built mesh: a 4x4 grid of unit quads in z = 0 plus a tilted triangle above it.
        api::Geometry grid;
        std::vector<float> p;
        std::vector<uint32_t> idx;
        for (int j = 0; j <= 4; ++j)
            for (int i = 0; i <= 4; ++i) p.insert(p.end(), {float(i), float(j), 0.f});
        for (int j = 0; j < 4; ++j)
            for (int i = 0; i < 4; ++i) {
                uint32_t a = j * 5 + i, b = a + 1, c = a + 5, d = c + 1;
                idx.insert(idx.end(), {a, b, d, a, d, c});
            }
        p.insert(p.end(), {0.5f, 0.5f, 1.f, 3.5f, 1.f, 1.5f, 1.f, 3.5f, 0.8f});
        idx.insert(idx.end(), {25, 26, 27});
        grid.addTriangleMesh(p, idx);
        std::vector<V3> verts = toV3(p);
        auto mine = [&](const api::Ray& r, api::Hit& hit) { return bruteForce(verts, idx, r, hit); };
        api::ValidationOptions opt;
        opt.rays = 20000;
        opt.seed = 7;
        api::ValidationReport good = api::validate(grid, mine, {}, opt);
        std::printf("user brute force: %zu rays, %zu agree, %zu ties, %zu errors\n", good.rays, good.agreements,
                    good.ties, good.errors);
        check(good.rays == opt.rays && good.errors == 0, "a correct user intersector validates with 0 errors");

        // A subtly broken intersector (reports primId + 1) must be caught.
        auto broken = [&](const api::Ray& r, api::Hit& hit) {
            if (!mine(r, hit)) return false;
            hit.primId = (hit.primId + 1) % uint32_t(idx.size() / 3);
            return true;
        };
        api::ValidationReport bad = api::validate(grid, broken, {}, opt);
        check(bad.errors > bad.rays / 4 && !bad.examples.empty(), "a broken user intersector is reported");
        check(bad.json().find("\"errors\"") != std::string::npos, "the report prints as JSON");

        // 2. A scene file, with our BVH checked against Embree through the same API.
        api::Geometry scene = api::Geometry::load(argv[1]);
        check(scene.primitiveCount() > 0, "Geometry::load reads the scene");
        for (const std::string& name : api::accelNames()) {
            api::Structure s(scene, name, 1);
            api::ValidationOptions o;
            o.rays = 20000;
            api::ValidationReport r = api::validate(scene, s, o);
            std::printf("%s: %zu rays, %zu ties, %zu errors (build %.4f s, %zu bytes)\n", name.c_str(), r.rays, r.ties,
                        r.errors, s.buildSeconds(), s.memoryBytes());
            check(r.errors == 0, ("structure " + name + " matches Embree").c_str());
        }
        std::vector<api::Ray> rays = api::generateRays(scene, "primary", 100, 1);
        api::Structure embree(scene);
        int hits = 0;
        for (const api::Ray& r : rays) {
            api::Hit h;
            hits += embree.intersect(r, h) ? 1 : 0;
        }
        check(rays.size() == 100 && hits > 50, "generateRays + Structure::intersect");

        // 3. Meshes where only a careful tie rule gives honest verdicts (tests/accel_pathologies.h):
        // overlapping coplanar triangles and long slivers. The user's double-precision brute force
        // and every structure validate with 0 errors.
        for (int a = 2; a < argc; ++a) {
            std::vector<float> pp;
            std::vector<uint32_t> ii;
            readObj(argv[a], pp, ii);
            api::Geometry mesh;
            mesh.addTriangleMesh(pp, ii);
            std::vector<V3> vv = toV3(pp);
            // Every ray crosses thousands of a hairball's triangles: few rays for the brute force.
            api::ValidationOptions o;
            o.rays = std::max<size_t>(200, 20000000 / (ii.size() / 3));
            o.seed = 3;
            auto user = [&](const api::Ray& r, api::Hit& hit) { return bruteForce(vv, ii, r, hit); };
            api::ValidationReport u = api::validate(mesh, user, {}, o);
            std::printf("%s, user brute force: %zu rays, %zu ties, %zu errors\n", argv[a], u.rays, u.ties, u.errors);
            check(u.errors == 0, "a correct user intersector validates with 0 errors on a pathology mesh");
            if (u.errors) std::printf("%s\n", u.json().c_str());
            for (const std::string& name : api::accelNames()) {
                if (name == "brute" || name == "embree") continue;
                api::Structure s(mesh, name, 1);
                o.rays = 2000;
                api::ValidationReport r = api::validate(mesh, s, o);
                std::printf("%s, %s: %zu rays, %zu ties, %zu errors\n", argv[a], name.c_str(), r.rays, r.ties, r.errors);
                check(r.errors == 0, ("structure " + name + " matches Embree on a pathology mesh").c_str());
            }
        }

        // 4. Errors come back as exceptions, not crashes.
        bool threw = false;
        try {
            api::Structure nope(scene, "no-such-structure");
        } catch (const std::invalid_argument&) {
            threw = true;
        }
        check(threw, "an unknown structure name throws std::invalid_argument");
        threw = false;
        try {
            api::Geometry::load("/nonexistent/scene.gltf");
        } catch (const std::runtime_error& e) {
            threw = std::string(e.what()).find("/nonexistent/scene.gltf") != std::string::npos;
        }
        check(threw, "a missing file throws std::runtime_error naming it");
    } catch (const std::exception& e) {
        std::fprintf(stderr, "consumer: unexpected exception: %s\n", e.what());
        return 1;
    }
    return failures == 0 ? 0 : 1;
}
