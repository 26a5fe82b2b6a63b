// `tessera view`: the fly camera (motion = speed × held time at any frame rate, printed arguments
// that reproduce the camera bit for bit), the script parser, the preview session (still passes equal
// a batch render bit for bit, a change abandons the pass and restarts, moving frames are reduced),
// and the real window under Xvfb driven by xdotool (tests/test_view_window.cpp).
#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include <chrono>
#include <cstring>
#include <thread>

#include "accel/accel.h"
#include "core/error.h"
#include "render/film.h"
#include "render/renderer.h"
#include "scene/gltf_loader.h"
#include "test_helpers.h"
#include "view/fly_camera.h"
#include "view/preview.h"
#include "view/script.h"

using namespace tessera;
using namespace tessera::view;

namespace {

CameraDesc lookingAt(Vec3f eye, Vec3f target) {
    CameraDesc d;
    d.cameraToWorld = glm::inverse(glm::lookAt(eye, target, Vec3f(0, 1, 0)));
    d.yfov = 0.7f;
    return d;
}

/// Replays the same key timeline on a camera advanced at a given frame interval.
FlyCamera replay(double frameSeconds) {
    FlyCamera cam(lookingAt(Vec3f(1, 2, 3), Vec3f(1, 2, 2)), 2.5f);
    struct Ev {
        double t;
        MoveKey k;
        bool down;
    };
    const Ev events[] = {{0.10, MoveKey::Forward, true}, {0.73, MoveKey::Right, true}, {1.10, MoveKey::Forward, false},
                         {1.37, MoveKey::Right, false},  {1.50, MoveKey::Up, true},    {1.90, MoveKey::Up, false}};
    size_t next = 0;
    for (double t = 0.0; t < 2.5; t += frameSeconds) {
        for (; next < std::size(events) && events[next].t <= t; ++next) cam.setKey(events[next].k, events[next].down, events[next].t);
        cam.advanceTo(t);
    }
    for (; next < std::size(events); ++next) cam.setKey(events[next].k, events[next].down, events[next].t);
    cam.advanceTo(2.5);
    return cam;
}

}  // namespace

TEST(FlyCamera, DistanceIsSpeedTimesHeldTimeWhateverTheFrameRate) {
    FlyCamera slow = replay(1.0 / 7.0), fast = replay(1.0 / 240.0), odd = replay(0.0371);
    // Forward alone 0.63 s, forward+right 0.37 s (diagonal at the same speed), right alone 0.27 s, up 0.4 s.
    const double expected = 2.5 * (0.63 + 0.37 + 0.27 + 0.40);
    for (const FlyCamera* c : {&slow, &fast, &odd}) {
        EXPECT_NEAR(c->distanceTravelled(), expected, 1e-9);
        EXPECT_NEAR(glm::length(c->eye() - fast.eye()), 0.0, 1e-5);
    }
    // Looking down −z from (1,2,3): forward 0.63 s, then the diagonal, right (+x), up (+y).
    const double d = 2.5 * 0.37 / std::sqrt(2.0);
    Vec3f want(1.f + float(d + 2.5 * 0.27), 2.f + 2.5f * 0.4f, 3.f - float(2.5 * 0.63 + d));
    EXPECT_NEAR(fast.eye().x, want.x, 1e-5);
    EXPECT_NEAR(fast.eye().y, want.y, 1e-5);
    EXPECT_NEAR(fast.eye().z, want.z, 1e-5);
}

TEST(FlyCamera, ShiftIsFasterAndTheMouseTurnsWithoutRoll) {
    FlyCamera cam(lookingAt(Vec3f(0), Vec3f(0, 0, -1)), 1.f);
    cam.setFast(true, 0.0);
    cam.setKey(MoveKey::Back, true, 0.0);
    cam.setKey(MoveKey::Back, false, 0.5);
    EXPECT_NEAR(cam.eye().z, 0.5f * cam.fastFactor, 1e-6);
    EXPECT_FALSE(cam.anyKeyHeld());
    cam.look(100.0, -10000.0, 0.6);  // far up: pitch stops short of vertical
    EXPECT_NEAR(cam.yawRadians(), 100.0 * cam.sensitivityRadiansPerPixel, 1e-6);
    EXPECT_NEAR(cam.pitchRadians(), 89.0 * kPi / 180.0, 1e-5);
    CameraDesc d = cam.desc();
    Vec3f right(d.cameraToWorld[0]);
    EXPECT_NEAR(right.y, 0.f, 1e-6) << "no roll: the camera's x axis stays horizontal";
    Vec3f f = -Vec3f(d.cameraToWorld[2]);
    EXPECT_NEAR(glm::length(f - cam.forward()), 0.f, 1e-5);
    EXPECT_TRUE(cam.takeChanged());
    EXPECT_FALSE(cam.takeChanged());
}

TEST(FlyCamera, PrintedRenderArgumentsReproduceTheCameraBitForBit) {
    FlyCamera cam(lookingAt(Vec3f(0.1f, 0.7f, 3.3f), Vec3f(0.2f, 0.5f, 0.f)), 1.37f);
    EXPECT_EQ(cam.desc().cameraToWorld, lookingAt(Vec3f(0.1f, 0.7f, 3.3f), Vec3f(0.2f, 0.5f, 0.f)).cameraToWorld)
        << "unmoved: the start camera's own matrix";
    cam.setKey(MoveKey::Forward, true, 0.0);
    cam.look(13.0, 7.0, 0.31);
    cam.setKey(MoveKey::Forward, false, 0.77);
    std::string args = cam.renderArguments();
    // Parse exactly as `render --look-at ... --fov ...` does (app/render_command.cpp).
    float v[6];
    double fovDeg = 0.0;
    ASSERT_EQ(std::sscanf(args.c_str(), "--look-at %f,%f,%f,%f,%f,%f --fov %lf", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5], &fovDeg), 7)
        << args;
    Mat4f m = glm::inverse(glm::lookAt(Vec3f(v[0], v[1], v[2]), Vec3f(v[3], v[4], v[5]), Vec3f(0, 1, 0)));
    Mat4f viewed = cam.desc().cameraToWorld;
    EXPECT_EQ(std::memcmp(&m, &viewed, sizeof m), 0) << args;
    EXPECT_EQ(float(fovDeg * kPi / 180.0), 0.7f);
    for (float fov : {0.1f, 0.5f, 0.6911112f, 0.9487f, 1.2f, 2.9f}) {
        double deg = std::strtod(fovArgumentDegrees(fov).c_str(), nullptr);
        EXPECT_EQ(float(deg * kPi / 180.0), fov);
    }
}

TEST(ViewScript, ParsesSortsAndNamesTheBadLine) {
    auto ev = parseScript("# walk\n1.5 up W\n0.5 down w   # forward\n\n2 look 10 -4\n2 press 3\n3 click\n4 quit\n", "s.txt");
    ASSERT_EQ(ev.size(), 6u);
    EXPECT_EQ(ev[0].kind, ScriptEvent::Kind::Down);
    EXPECT_EQ(ev[0].key, "w");
    EXPECT_EQ(ev[1].kind, ScriptEvent::Kind::Up);
    EXPECT_EQ(ev[1].line, 2);
    EXPECT_EQ(ev[2].kind, ScriptEvent::Kind::Look);
    EXPECT_EQ(ev[2].dy, -4.0);
    EXPECT_EQ(ev[3].key, "3");
    EXPECT_EQ(ev[5].kind, ScriptEvent::Kind::Quit);
    auto message = [](const std::string& text) {
        try {
            parseScript(text, "s.txt");
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    EXPECT_EQ(message("1 down w\nx down w\n"), "s.txt:2: 'x' is not a time in seconds");
    EXPECT_EQ(message("-1 down w\n"), "s.txt:1: the time must be a finite number of seconds >= 0");
    EXPECT_EQ(message("1 down f1\n"), "s.txt:1: unknown key 'f1' (a letter, a digit, space, ctrl, shift or escape)");
    EXPECT_EQ(message("1 jump\n"), "s.txt:1: unknown event 'jump' (down, up, press, look, click, quit)");
    EXPECT_EQ(message("1 look 3\n"), "s.txt:1: look needs DX DY in pixels");
    EXPECT_EQ(message("1 quit now\n"), "s.txt:1: unexpected 'now' after the event");
    EXPECT_THROW(readScript("/nonexistent/script.txt"), InputError);
}

namespace {

struct LoadedScene {
    Scene scene;
    std::unique_ptr<Accel> accel;
};

LoadedScene loadWithEmbree(const std::string& relative) {
    LoadedScene s{test::loadSourceScene(relative), nullptr};
    s.accel = createAccel("embree", s.scene.geometry);
    return s;
}

PreviewSettings smallPreview(int w, int h, uint32_t sppLimit) {
    PreviewSettings p;
    p.width = w;
    p.height = h;
    p.threads = 2;
    p.seed = 7;
    p.sppLimit = sppLimit;
    return p;
}

}  // namespace

TEST(PreviewSession, StillPassesEqualABatchRenderBitForBit) {
    LoadedScene s = loadWithEmbree("scenes/sphere-cornell/sphere-cornell.gltf");
    const int W = 48, H = 36;
    const uint32_t spp = 6;
    for (const char* integrator : {"ptnee", "bdpt"}) {
        PreviewSession session(s.scene, *s.accel, smallPreview(W, H, spp), *s.scene.camera, integrator);
        ASSERT_TRUE(session.waitForSpp(spp, 60.0));
        auto frame = session.currentFullFrame();
        ASSERT_TRUE(frame);
        EXPECT_EQ(frame->spp, spp);
        EXPECT_EQ(frame->samples, uint64_t(W) * H * spp);

        // The batch render: `tessera render --spp 6 --seed 7`, passes of 1, 1, 2, 2 spp.
        Camera camera(*s.scene.camera, W, H);
        RenderContext ctx{s.scene, *s.accel, camera, s.scene.settings.maxDepth};
        Film film(W, H);
        std::unique_ptr<Integrator> batchIntegrator = createIntegrator(integrator);
        renderImage(ctx, *batchIntegrator, film, RenderOptions{.spp = int(spp), .threads = 1, .seed = 7});
        std::vector<float> batch = film.rgba();
        ASSERT_EQ(frame->rgba.size(), batch.size());
        if (std::string(integrator) == "ptnee") {
            // Same samples, same per-pixel summation order: the same bits.
            EXPECT_EQ(std::memcmp(frame->rgba.data(), batch.data(), batch.size() * sizeof(float)), 0);
        } else {
            // BDPT's splats are merged per pass: another order of the same additions.
            for (size_t i = 0; i < batch.size(); ++i) ASSERT_NEAR(frame->rgba[i], batch[i], 1e-4f * (1.f + std::abs(batch[i]))) << i;
        }
    }
}

TEST(PreviewSession, ACameraChangeAbandonsThePassAndRestartsAccumulation) {
    LoadedScene s = loadWithEmbree("scenes/sphere-cornell/sphere-cornell.gltf");
    // Big enough that a pass (1 spp) takes far longer than one 32x32 tile.
    PreviewSession session(s.scene, *s.accel, smallPreview(320, 240, 0), *s.scene.camera, "ptnee");
    ASSERT_TRUE(session.waitForSpp(1, 60.0));
    std::this_thread::sleep_for(std::chrono::milliseconds(30));  // the second pass is under way
    FlyCamera fly(*s.scene.camera, 1.f);
    fly.look(20.0, 0.0, 0.0);
    auto t0 = std::chrono::steady_clock::now();
    session.setCamera(fly.desc(), false);
    EXPECT_FALSE(session.currentFullFrame()) << "the old accumulation is no longer current";
    ASSERT_TRUE(session.waitForSpp(1, 60.0));
    double restartToFrame = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    auto frame = session.currentFullFrame();
    ASSERT_TRUE(frame);
    EXPECT_EQ(frame->spp, 1u) << "accumulation restarted";
    EXPECT_EQ(frame->camera.cameraToWorld, fly.desc().cameraToWorld);
    PreviewCounters c = session.counters();
    EXPECT_EQ(c.restarts, 2u);
    EXPECT_GE(c.passesAbandoned, 1u) << "the pass in flight was dropped, not finished";
    // Abandoning within a tile: the new first frame comes about one pass after the change, not two.
    ASSERT_TRUE(c.firstFullFrameSeconds);
    EXPECT_LT(restartToFrame, 1.6 * *c.firstFullFrameSeconds + 0.2) << "restart to frame " << restartToFrame;
}

TEST(PreviewSession, AMovingCameraGetsReducedFramesThenRefinesAtFullResolution) {
    LoadedScene s = loadWithEmbree("scenes/cornell-box/cornell-box.gltf");
    PreviewSession session(s.scene, *s.accel, smallPreview(320, 240, 2), *s.scene.camera, "ptnee");
    ASSERT_TRUE(session.waitForSpp(1, 60.0));
    FlyCamera fly(*s.scene.camera, 1.f);
    uint64_t version = 0;
    while (session.newFrame(version)) {}
    fly.setKey(MoveKey::Forward, true, 0.0);
    fly.advanceTo(0.1);
    session.setCamera(fly.desc(), true);
    std::shared_ptr<const PreviewFrame> f;
    for (int i = 0; i < 6000 && !(f && f->reduced); ++i) {
        if (auto n = session.newFrame(version)) f = n;
        else std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    ASSERT_TRUE(f && f->reduced);
    EXPECT_GE(f->reduction, 2);
    EXPECT_LE(f->reduction, 8);
    EXPECT_EQ(f->width, 320 / f->reduction);
    EXPECT_EQ(f->height, 240 / f->reduction);
    fly.setKey(MoveKey::Forward, false, 0.2);
    session.setCamera(fly.desc(), false);
    ASSERT_TRUE(session.waitForSpp(2, 60.0));
    auto full = session.currentFullFrame();
    ASSERT_TRUE(full);
    EXPECT_FALSE(full->reduced);
    EXPECT_EQ(full->width, 320);
    EXPECT_EQ(full->camera.cameraToWorld, fly.desc().cameraToWorld);
    EXPECT_GE(session.counters().reducedFrames, 1u);
}

TEST(PreviewSession, SpeedFollowsWhatTheCameraSees) {
    // The sphere Cornell box's walls are spheres of radius 1e4: the bounds would give a speed in
    // the thousands; the median hit distance gives a room-sized one.
    LoadedScene s = loadWithEmbree("scenes/sphere-cornell/sphere-cornell.gltf");
    float speed = speedForView(*s.accel, *s.scene.camera);
    Bounds3f b = s.accel->bounds();
    EXPECT_GT(speed, 0.f);
    EXPECT_LT(speed, 0.01f * glm::length(b.upper - b.lower));
}
