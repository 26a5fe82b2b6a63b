#pragma once
/// \file fly_camera.h
/// The preview's first-person camera: an eye, a yaw and a pitch (no roll), moved by held keys at a
/// speed in scene units per second and turned by mouse motion. Motion is integrated over the exact
/// time each key was held (event timestamps, not frame counts), so the distance travelled is
/// speed × held time whatever the frame rate.
#include <string>

#include "accel/accel.h"
#include "scene/camera.h"

namespace tessera::view {

/// Movement keys (index into FlyCamera's held-key table).
enum class MoveKey { Forward, Back, Left, Right, Down, Up, Count };

class FlyCamera {
public:
    /// Starts at `start` (its position and viewing direction; any roll is dropped once the camera
    /// moves). `speed` in scene units per second.
    FlyCamera(const CameraDesc& start, float speed);

    /// Advances the clock to `seconds`, moving the eye along the held keys' directions for the time
    /// since the last call (a call with an earlier time than the last one moves nothing).
    void advanceTo(double seconds);
    /// A key goes down or up at time `seconds` (advances to it first).
    void setKey(MoveKey key, bool down, double seconds);
    /// Shift: `fastFactor` times faster while held.
    void setFast(bool fast, double seconds);
    /// Mouse motion in pixels at time `seconds`: yaw right for +dx, pitch down for +dy.
    void look(double dxPixels, double dyPixels, double seconds);
    /// Releases every key (focus lost, mouse released) at time `seconds`.
    void releaseAll(double seconds);

    bool anyKeyHeld() const;
    /// True once the camera has changed since the last call (and clears the flag).
    bool takeChanged();

    /// The camera to render: the start camera's exact matrix until the first change, then
    /// glm::lookAt(eye, eye + forward, +y) like `render --look-at`.
    CameraDesc desc() const;
    /// "--look-at ex,ey,ez,tx,ty,tz --fov D": `tessera render` with these options renders the same
    /// camera bit for bit once the camera has moved (floats printed to round-trip).
    std::string renderArguments() const;

    Vec3f eye() const { return eye_; }
    Vec3f forward() const;
    float yawRadians() const { return yaw_; }
    float pitchRadians() const { return pitch_; }
    float speed() const { return speed_; }
    /// Total path length travelled (scene units), for the tests and the status line.
    double distanceTravelled() const { return travelled_; }

    float sensitivityRadiansPerPixel = 0.0025f;
    float fastFactor = 4.f;

private:
    CameraDesc start_;
    Vec3f eye_;
    float yaw_ = 0.f, pitch_ = 0.f;
    float speed_;
    bool held_[int(MoveKey::Count)] = {};
    bool fast_ = false, moved_ = false, changed_ = false;
    double now_ = 0.0, travelled_ = 0.0;
};

/// The fov a --fov argument must carry so that `render` (which converts degrees to radians as
/// float(deg * kPi / 180)) gets exactly `yfovRadians` back: printed with enough digits to round-trip.
std::string fovArgumentDegrees(float yfovRadians);

/// A preview speed for this view of the scene, in units per second: half the median distance from
/// the eye to what a 9x9 grid of camera rays hits (so crossing the visible space takes about two
/// seconds whatever the scene's units). The bounding box would mislead: the sphere Cornell box's
/// walls are spheres of radius 1e4. Without any hit: a quarter of the bounds' diagonal.
float speedForView(const Accel& accel, const CameraDesc& camera);

}  // namespace tessera::view
