#include "view/fly_camera.h"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <utility>
#include <vector>

namespace tessera::view {
namespace {

constexpr float kMaxPitch = 89.f * kPi / 180.f;  // short of straight up/down, where lookAt's +y up degenerates
const Vec3f kWorldUp(0.f, 1.f, 0.f);

/// Shortest %.Ng text of `v` that reads back as exactly `v`.
std::string roundTrip(float v) {
    char buf[48];
    for (int digits = 6; digits <= 9; ++digits) {
        std::snprintf(buf, sizeof buf, "%.*g", digits, double(v));
        if (std::strtof(buf, nullptr) == v) break;
    }
    return buf;
}

}  // namespace

FlyCamera::FlyCamera(const CameraDesc& start, float speed) : start_(start), speed_(speed) {
    eye_ = Vec3f(start.cameraToWorld[3]);
    Vec3f f = glm::normalize(-Vec3f(start.cameraToWorld[2]));  // the camera looks down its local −z
    yaw_ = std::atan2(f.x, -f.z);
    pitch_ = std::clamp(std::asin(std::clamp(f.y, -1.f, 1.f)), -kMaxPitch, kMaxPitch);
}

Vec3f FlyCamera::forward() const {
    return Vec3f(std::sin(yaw_) * std::cos(pitch_), std::sin(pitch_), -std::cos(yaw_) * std::cos(pitch_));
}

void FlyCamera::advanceTo(double seconds) {
    double dt = seconds - now_;
    if (!(dt > 0.0)) return;
    now_ = seconds;
    auto h = [&](MoveKey k) { return held_[int(k)] ? 1.f : 0.f; };
    Vec3f f = forward(), right = glm::normalize(glm::cross(f, kWorldUp));
    Vec3f dir = f * (h(MoveKey::Forward) - h(MoveKey::Back)) + right * (h(MoveKey::Right) - h(MoveKey::Left)) +
                kWorldUp * (h(MoveKey::Up) - h(MoveKey::Down));
    float len = glm::length(dir);
    if (!(len > 0.f)) return;
    // Diagonals are no faster than straight lines: the speed is that of the combined direction.
    double step = double(speed_) * (fast_ ? double(fastFactor) : 1.0) * dt;
    eye_ += dir * float(step / double(len));
    travelled_ += step;
    moved_ = changed_ = true;
}

void FlyCamera::setKey(MoveKey key, bool down, double seconds) {
    advanceTo(seconds);
    held_[int(key)] = down;
}

void FlyCamera::setFast(bool fast, double seconds) {
    advanceTo(seconds);
    fast_ = fast;
}

void FlyCamera::look(double dxPixels, double dyPixels, double seconds) {
    advanceTo(seconds);
    if (dxPixels == 0.0 && dyPixels == 0.0) return;
    yaw_ = float(std::remainder(double(yaw_) + dxPixels * sensitivityRadiansPerPixel, 2.0 * kPi));
    pitch_ = std::clamp(float(double(pitch_) - dyPixels * sensitivityRadiansPerPixel), -kMaxPitch, kMaxPitch);
    moved_ = changed_ = true;
}

void FlyCamera::releaseAll(double seconds) {
    advanceTo(seconds);
    std::fill(std::begin(held_), std::end(held_), false);
    fast_ = false;
}

bool FlyCamera::anyKeyHeld() const { return std::any_of(std::begin(held_), std::end(held_), [](bool b) { return b; }); }

bool FlyCamera::takeChanged() { return std::exchange(changed_, false); }

CameraDesc FlyCamera::desc() const {
    if (!moved_) return start_;
    CameraDesc d = start_;
    // The same expression as `render --look-at` (app/render_command.cpp), from the same floats, so
    // the printed arguments reproduce this matrix bit for bit.
    Vec3f target = eye_ + forward();
    d.cameraToWorld = glm::inverse(glm::lookAt(eye_, target, kWorldUp));
    return d;
}

std::string FlyCamera::renderArguments() const {
    Vec3f target = eye_ + forward();
    std::string s = "--look-at ";
    const float v[6] = {eye_.x, eye_.y, eye_.z, target.x, target.y, target.z};
    for (int i = 0; i < 6; ++i) {
        s += i ? "," : "";
        s += roundTrip(v[i]);
    }
    return s + " --fov " + fovArgumentDegrees(start_.yfov);
}

std::string fovArgumentDegrees(float yfovRadians) {
    // render: yfov = float(fovDeg * kPi / 180.0) with fovDeg parsed as a double. Start from the exact
    // inverse and step to neighbouring doubles until the conversion gives the float back.
    double deg = double(yfovRadians) * 180.0 / double(kPi);
    char buf[48];
    for (int tries = 0; tries < 64; ++tries) {
        std::snprintf(buf, sizeof buf, "%.17g", deg);
        double parsed = std::strtod(buf, nullptr);
        float back = float(parsed * kPi / 180.0);
        if (back == yfovRadians) return buf;
        deg = back < yfovRadians ? std::nextafter(deg, 1e9) : std::nextafter(deg, -1e9);
    }
    return buf;
}

float speedForView(const Accel& accel, const CameraDesc& desc) {
    constexpr int kGrid = 9;
    Camera camera(desc, kGrid, kGrid);
    std::vector<float> distances;
    for (int y = 0; y < kGrid; ++y)
        for (int x = 0; x < kGrid; ++x) {
            Ray ray = camera.generateRay(Vec2f(float(x) + 0.5f, float(y) + 0.5f), Vec2f(0.5f));
            Hit hit;
            if (accel.intersect(ray, hit) && std::isfinite(hit.t)) distances.push_back(hit.t);
        }
    if (!distances.empty()) {
        auto mid = distances.begin() + std::ptrdiff_t(distances.size() / 2);
        std::nth_element(distances.begin(), mid, distances.end());
        if (*mid > 0.f) return 0.5f * *mid;
    }
    Bounds3f b = accel.bounds();
    float diag = glm::length(b.upper - b.lower);
    return std::isfinite(diag) && diag > 0.f ? 0.25f * diag : 1.f;
}

}  // namespace tessera::view
