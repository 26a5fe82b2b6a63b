/// \file view_command.cpp
/// `tessera view SCENE`: an SDL2 window over the progressive preview (view/preview.h). Input →
/// FlyCamera (view/fly_camera.h) → PreviewSession::setCamera (restart) → passes → display through
/// the same OCIO transform and 8-bit quantisation as the PNG output (io::displayRgb8).
///
/// SDL2 rather than GLFW + OpenGL: the image is computed on the CPU anyway, so the window only has
/// to show a 960×540 RGB buffer, which SDL's software renderer does in well under a millisecond
/// without any GL driver (under Xvfb there is no Mesa context to get right), and SDL's relative
/// mouse mode gives the captured, unbounded mouse look with one call.
#include <SDL.h>
#include <glm/gtc/matrix_transform.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <optional>
#include <sstream>

#include "accel/accel.h"
#include "app/commands.h"
#include "app/scene_options.h"
#include "core/error.h"
#include "core/fnv1a.h"
#include "core/version.h"
#include "integrators/integrator.h"
#include "io/display_transform.h"
#include "io/image_output.h"
#include "render/film.h"
#include "render/progress.h"
#include "scene/gltf_loader.h"
#include "view/fly_camera.h"
#include "view/preview.h"
#include "view/script.h"

namespace tessera::app {
namespace {

struct ViewArgs : SceneOptions {
    std::string output, accel = "embree", display = "sRGB", view = "Standard", script;
    int threads = 0;
    double exitAfter = 0.0, speed = 0.0;
    bool printCamera = false;
};



/// The window: an SDL software renderer and one streaming RGB texture, re-made when the frame size
/// changes (reduced frames are stretched to the window with nearest-neighbour filtering).
class Window {
public:
    Window(const std::string& title, int width, int height) {
        SDL_SetHint(SDL_HINT_RENDER_DRIVER, "software");
        SDL_SetHint(SDL_HINT_FRAMEBUFFER_ACCELERATION, "0");  // the plain X11 (XShm) framebuffer: no GL driver loaded
        SDL_SetHint(SDL_HINT_RENDER_SCALE_QUALITY, "nearest");
        SDL_SetHint(SDL_HINT_NO_SIGNAL_HANDLERS, "0");  // Ctrl-C arrives as SDL_QUIT: the same clean close
        // Without a display SDL falls back to its "offscreen" driver, which would "show" the window
        // to nobody: only a driver that puts a window on a screen counts (or one asked for by name
        // through SDL_VIDEODRIVER). Wayland's client library prints its own complaint when
        // XDG_RUNTIME_DIR is unset; with no WAYLAND_DISPLAY it cannot connect anyway.
        const char* asked = std::getenv("SDL_VIDEODRIVER");
        const bool x11 = std::getenv("DISPLAY") != nullptr, wayland = std::getenv("WAYLAND_DISPLAY") != nullptr;
        const bool screenless = !asked && !x11 && !wayland;
        if (!asked && !screenless) SDL_SetHint(SDL_HINT_VIDEODRIVER, x11 && wayland ? "x11,wayland" : x11 ? "x11" : "wayland");
        if (screenless || SDL_Init(SDL_INIT_VIDEO) != 0 ||
            (!asked && (std::string(SDL_GetCurrentVideoDriver()) == "offscreen" || std::string(SDL_GetCurrentVideoDriver()) == "dummy"))) {
            std::string why = screenless ? "neither DISPLAY nor WAYLAND_DISPLAY is set" : SDL_GetError();
            if (!screenless) SDL_Quit();
            throw InputError("tessera view needs a display, and none could be opened (" + why +
                             "); set DISPLAY, or render without a window: tessera render SCENE");
        }
        window_ = SDL_CreateWindow(title.c_str(), SDL_WINDOWPOS_CENTERED, SDL_WINDOWPOS_CENTERED, width, height, SDL_WINDOW_SHOWN);
        if (window_) renderer_ = SDL_CreateRenderer(window_, -1, SDL_RENDERER_SOFTWARE);
        if (!window_ || !renderer_) {
            std::string why = SDL_GetError();
            close();
            throw InputError("tessera view could not open a " + std::to_string(width) + "x" + std::to_string(height) +
                             " window (" + why + "); render without a window: tessera render SCENE");
        }
    }
    ~Window() { close(); }
    Window(const Window&) = delete;
    Window& operator=(const Window&) = delete;

    void show(int width, int height, const std::vector<uint8_t>& rgb) {
        if (!texture_ || width != texW_ || height != texH_) {
            if (texture_) SDL_DestroyTexture(texture_);
            texture_ = SDL_CreateTexture(renderer_, SDL_PIXELFORMAT_RGB24, SDL_TEXTUREACCESS_STREAMING, width, height);
            if (!texture_) throw std::runtime_error(std::string("SDL_CreateTexture: ") + SDL_GetError());
            texW_ = width;
            texH_ = height;
        }
        SDL_UpdateTexture(texture_, nullptr, rgb.data(), 3 * width);
        present();
    }
    void present() {
        SDL_RenderClear(renderer_);
        if (texture_) SDL_RenderCopy(renderer_, texture_, nullptr, nullptr);
        SDL_RenderPresent(renderer_);
    }
    void setTitle(const std::string& t) { SDL_SetWindowTitle(window_, t.c_str()); }
    void captureMouse(bool on) {
        SDL_SetRelativeMouseMode(on ? SDL_TRUE : SDL_FALSE);
        captured_ = on;
    }
    bool mouseCaptured() const { return captured_; }

private:
    void close() {
        if (texture_) SDL_DestroyTexture(texture_);
        if (renderer_) SDL_DestroyRenderer(renderer_);
        if (window_) SDL_DestroyWindow(window_);
        texture_ = nullptr;
        renderer_ = nullptr;
        window_ = nullptr;
        SDL_Quit();
    }
    SDL_Window* window_ = nullptr;
    SDL_Renderer* renderer_ = nullptr;
    SDL_Texture* texture_ = nullptr;
    int texW_ = 0, texH_ = 0;
    bool captured_ = false;
};

/// A script key name → the SDL key code the window would report for it.
SDL_Keycode keyFromName(const std::string& k) {
    if (k == "space") return SDLK_SPACE;
    if (k == "ctrl") return SDLK_LCTRL;
    if (k == "shift") return SDLK_LSHIFT;
    if (k == "escape") return SDLK_ESCAPE;
    return SDL_Keycode(k[0]);  // letters and digits: SDL key codes are their lower-case ASCII
}

std::optional<view::MoveKey> moveKey(SDL_Keycode k) {
    switch (k) {
        case SDLK_w: return view::MoveKey::Forward;
        case SDLK_s: return view::MoveKey::Back;
        case SDLK_a: return view::MoveKey::Left;
        case SDLK_d: return view::MoveKey::Right;
        case SDLK_q: case SDLK_LCTRL: case SDLK_RCTRL: return view::MoveKey::Down;
        case SDLK_e: case SDLK_SPACE: return view::MoveKey::Up;
        default: return std::nullopt;
    }
}

std::string fixed(double v, int decimals) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
    return buf;
}

/// The interactive session: input handling, the camera, the preview and the window.
class Viewer {
public:
    Viewer(const ViewArgs& a, const Scene& scene, const Accel& accel, const RenderSettings& s)
        : a_(a), accel_(accel), settings_(s), display_(a.display, a.view),
          fly_(*scene.camera, a.speed > 0.0 ? float(a.speed) : view::speedForView(accel, *scene.camera)),
          window_("tessera view - " + stem(a.scene), s.width, s.height),
          session_(scene, accel, previewSettings(a, s), *scene.camera, s.integrator) {
        exr_ = a.output.empty() ? "out/" + stem(a.scene) + "-view.exr" : a.output;
        if (!a.script.empty()) script_ = view::readScript(a.script);
    }

    int run() {
        const uint64_t t0 = SDL_GetTicks64();
        window_.captureMouse(true);
        auto now = [&] { return double(SDL_GetTicks64() - t0) / 1000.0; };
        size_t nextScript = 0;
        double lastTitle = -1.0, lastShow = -1.0;
        uint64_t version = 0;
        std::shared_ptr<const view::PreviewFrame> pending;
        while (!quit_) {
            SDL_Event e;
            if (SDL_WaitEventTimeout(&e, 4)) {
                do handleEvent(e, double(int64_t(e.common.timestamp) - int64_t(t0)) / 1000.0);
                while (!quit_ && SDL_PollEvent(&e));
            }
            double t = now();
            // Scripted input, stamped with its own time so that motion is exact, not frame-quantised
            // (events are played once due, before the camera advances to now).
            for (; nextScript < script_.size() && script_[nextScript].seconds <= t && !quit_; ++nextScript)
                handleScript(script_[nextScript]);
            if (a_.exitAfter > 0.0 && t >= a_.exitAfter) quit_ = true;
            updateCamera(t);

            if (auto f = session_.newFrame(version)) pending = std::move(f);
            // Moving frames at once; still passes at most 20 times a second (the conversion costs
            // the render a little CPU each time).
            if (pending && (pending->reduced || t - lastShow >= 0.05)) {
                window_.show(pending->width, pending->height, io::displayRgb8(pending->width, pending->height, pending->rgba.data(), display_));
                shown_ = pending;
                pending.reset();
                lastShow = t;
            }
            if (t - lastTitle >= 0.25) {
                window_.setTitle(title());
                lastTitle = t;
            }
        }
        if (a_.printCamera) printCamera();
        return 0;
    }

private:
    static view::PreviewSettings previewSettings(const ViewArgs& a, const RenderSettings& s) {
        view::PreviewSettings p;
        p.width = s.width;
        p.height = s.height;
        p.threads = a.threads;
        p.seed = s.seed;
        p.sampler = s.sampler;
        p.maxDepth = s.maxDepth;
        p.sppLimit = uint32_t(std::max(0, a.spp));
        return p;
    }

    /// `t`: the event's own time (FlyCamera ignores a time earlier than one it has seen).
    void handleEvent(const SDL_Event& e, double t) {
        switch (e.type) {
            case SDL_QUIT: quit_ = true; break;
            case SDL_KEYDOWN:
            case SDL_KEYUP:
                if (!e.key.repeat) onKey(e.key.keysym.sym, e.type == SDL_KEYDOWN, t);
                break;
            case SDL_MOUSEMOTION:
                if (window_.mouseCaptured()) onLook(e.motion.xrel, e.motion.yrel, t);
                break;
            case SDL_MOUSEBUTTONDOWN:
                if (!window_.mouseCaptured()) window_.captureMouse(true);
                break;
            case SDL_WINDOWEVENT:
                if (e.window.event == SDL_WINDOWEVENT_FOCUS_LOST) fly_.releaseAll(t);
                if (e.window.event == SDL_WINDOWEVENT_EXPOSED) window_.present();
                break;
            default: break;
        }
    }

    void handleScript(const view::ScriptEvent& e) {
        const double t = e.seconds;
        using K = view::ScriptEvent::Kind;
        switch (e.kind) {
            case K::Down: onKey(keyFromName(e.key), true, t); break;
            case K::Up: onKey(keyFromName(e.key), false, t); break;
            case K::Press:
                onKey(keyFromName(e.key), true, t);
                onKey(keyFromName(e.key), false, t);
                break;
            case K::Look: onLook(e.dx, e.dy, t); break;
            case K::Click:
                if (!window_.mouseCaptured()) window_.captureMouse(true);
                break;
            case K::Quit: quit_ = true; break;
        }
    }

    void onLook(double dx, double dy, double t) {
        fly_.look(dx, dy, t);
        lastLook_ = t;
    }

    void onKey(SDL_Keycode key, bool down, double t) {
        if (auto m = moveKey(key)) return fly_.setKey(*m, down, t);
        if (key == SDLK_LSHIFT || key == SDLK_RSHIFT) return fly_.setFast(down, t);
        if (!down) return;
        if (key == SDLK_ESCAPE) {
            window_.captureMouse(false);
            fly_.releaseAll(t);
        } else if (key == SDLK_p) {
            save();
        } else if (key == SDLK_c) {
            printCamera();
        } else if (key == SDLK_r) {
            session_.reset();
        } else if (key >= SDLK_1 && key <= SDLK_9) {
            std::vector<std::string> names = integratorNames();
            size_t i = size_t(key - SDLK_1);
            if (i < names.size()) session_.setIntegrator(names[i]);
        }
    }

    /// Sends a changed camera to the preview; a camera that stops moving restarts at full resolution.
    void updateCamera(double t) {
        fly_.advanceTo(t);
        bool moving = fly_.anyKeyHeld() || (lastLook_ >= 0.0 && t - lastLook_ < kLookSettleSeconds);
        if (fly_.takeChanged()) {
            session_.setCamera(fly_.desc(), moving);
            wasMoving_ = moving;
        } else if (wasMoving_ && !moving) {
            session_.setCamera(fly_.desc(), false);
            wasMoving_ = false;
        }
    }

    std::string title() const {
        std::string t = "tessera view - " + stem(a_.scene) + " - " + session_.integrator();
        if (!shown_) return t + " - starting";
        if (shown_->reduced)
            return t + " - moving: 1/" + std::to_string(shown_->reduction * shown_->reduction) + " of the pixels, " +
                   fixed(shown_->renderSeconds * 1000.0, 0) + " ms/frame";
        double rate = shown_->wallSeconds > 0 ? double(shown_->samples) / shown_->wallSeconds : 0.0;
        return t + " - " + std::to_string(shown_->spp) + " spp - " + fixed(rate / 1e6, 2) + " M samples/s - " +
               std::to_string(shown_->width) + "x" + std::to_string(shown_->height) + (window_.mouseCaptured() ? "" : " - click to look");
    }

    /// The C key (and --print-camera on exit): the `render` command line of this view, then a status line.
    void printCamera() {
        auto full = session_.currentFullFrame();
        view::PreviewCounters c = session_.counters();
        Vec3f eye = fly_.eye();
        std::cout << "tessera render " << a_.scene << " " << fly_.renderArguments() << " --resolution " << settings_.width << "x"
                  << settings_.height << " --integrator " << session_.integrator() << " --seed " << settings_.seed << " --sampler " << samplerName(settings_.sampler) << " --spp "
                  << (full ? full->spp : 1) << "\n";
        std::cout << "view-status spp=" << (full ? full->spp : 0) << " samples=" << (full ? full->samples : 0)
                  << " wall_seconds=" << (full ? full->wallSeconds : 0.0) << " render_seconds=" << (full ? full->renderSeconds : 0.0)
                  << " restarts=" << c.restarts << " abandoned=" << c.passesAbandoned << " reduced_frames=" << c.reducedFrames
                  << " first_full_frame_seconds=" << c.firstFullFrameSeconds.value_or(-1.0)
                  << " last_reduced_frame_seconds=" << c.lastReducedFrameSeconds << " eye=" << eye.x << "," << eye.y << "," << eye.z
                  << " travelled=" << fly_.distanceTravelled() << " speed=" << fly_.speed() << " yaw=" << fly_.yawRadians()
                  << " pitch=" << fly_.pitchRadians() << std::endl;
    }

    /// The P key: the current full-resolution image as EXR + PNG, with render's metadata.
    void save() {
        auto f = session_.currentFullFrame();
        if (!f) {
            printWarning("view: nothing to save yet: hold the camera still until the first full-resolution pass");
            return;
        }
        io::Metadata md = imageMetadata(a_.scene, settings_,
                                        ImageFacts{.integrator = f->integrator, .accel = std::string(accel_.name()), .spp = f->spp,
                                                   .samples = f->samples, .nonFiniteDropped = f->nonFiniteDropped,
                                                   .seconds = f->renderSeconds, .threads = f->threads});
        md.push_back({"tessera:view_camera", fly_.renderArguments()});
        std::string png = std::filesystem::path(exr_).replace_extension(".png").string();
        try {
            io::writeExr(exr_, f->width, f->height, f->rgba.data(), md);
            io::writePng(png, f->width, f->height, f->rgba.data(), display_, md);
            std::cout << "view: saved " << exr_ << ", " << png << " (" << f->spp << " spp)" << std::endl;
        } catch (const InputError& e) {
            printWarning(e.what());  // a failed save must not close the window
        }
    }

    static constexpr double kLookSettleSeconds = 0.15;  ///< mouse still this long: the camera has stopped

    const ViewArgs& a_;
    const Accel& accel_;
    RenderSettings settings_;
    io::DisplayTransform display_;
    view::FlyCamera fly_;
    Window window_;
    view::PreviewSession session_;  ///< after the window: its render thread stops before the window closes
    std::vector<view::ScriptEvent> script_;
    std::shared_ptr<const view::PreviewFrame> shown_;
    std::string exr_;
    double lastLook_ = -1.0;
    bool quit_ = false, wasMoving_ = false;
};

int runView(const ViewArgs& a) {
    Scene scene = loadScene(a);
    RenderSettings s = resolveSettings(a, scene);
    checkFilmFits(a, s);
    createIntegrator(s.integrator);  // an unknown name fails before the window opens
    if (!a.script.empty()) view::readScript(a.script);  // so does a bad script
    AccelOptions accelOptions;
    accelOptions.threads = a.threads;
    std::unique_ptr<Accel> accel = createAccel(a.accel, scene.geometry, accelOptions);
    Viewer viewer(a, scene, *accel, s);
    return viewer.run();
}

}  // namespace

Runner addViewCommand(CLI::App& app) {
    auto a = std::make_shared<ViewArgs>();
    CLI::App* cmd = app.add_subcommand("view", "Interactive preview: walk through a scene, the image refining progressively");
    cmd->add_option("SCENE", a->scene, "scene file (.gltf or .glb)")->required();
    cmd->add_option("-o,--output", a->output, "where P saves the image (EXR, and PNG beside it; default: out/<scene>-view.exr)");
    cmd->add_option("--spp", a->spp, "stop refining at this many samples per pixel (default: never)")->check(CLI::Range(1, 1 << 30));
    cmd->add_option("--threads", a->threads, "worker threads (default: all cores)")->check(CLI::Range(1, 4096));
    cmd->add_option("--seed", a->seed, "random seed (default: the scene's, else 0)")->check(CLI::NonNegativeNumber);
    addSamplerOption(*cmd, *a);
    cmd->add_option("--resolution", a->resolution, "window and image size WxH (default: the scene's)");
    cmd->add_option("--integrator", a->integrator, "light transport algorithm: " + commaSeparated(integratorNames()) + " (default: ptnee)");
    cmd->add_option("--accel", a->accel, "acceleration structure: " + commaSeparated(accelNames()) + " (default: embree)");
    cmd->add_option("--max-depth", a->maxDepth, "maximum number of bounces, -1 = unlimited")->check(CLI::Range(-1, 1 << 20));
    cmd->add_option("--look-at", a->lookAt, "start camera EX,EY,EZ,TX,TY,TZ: replaces the scene's camera");
    cmd->add_option("--fov", a->fovDeg, "vertical field of view in degrees")->check(CLI::Range(0.001, 179.0));
    cmd->add_option("--speed", a->speed, "movement speed in scene units per second (default: a quarter of the scene's diagonal)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--display", a->display, "OCIO display of the window and the PNG (default: sRGB)");
    cmd->add_option("--view", a->view, "OCIO view: Standard, \"ACES 1.0 SDR-video\", Raw (default: Standard)");
    cmd->add_option("--script", a->script, "timed input events to play (see src/view/script.h), for tests and demos");
    cmd->add_option("--exit-after", a->exitAfter, "close the window after this many seconds")->check(CLI::PositiveNumber);
    cmd->add_flag("--print-camera", a->printCamera, "on exit, print the view's render command line and a status line");
    cmd->add_flag("--allow-external-files", a->allowExternalFiles, "let the scene reference files outside its own folder");
    cmd->add_option("--max-memory", a->maxMemoryGiB, "memory limit in GiB for input files and the film (default: 16)")
        ->check(CLI::Range(0.001, 1e6));
    cmd->footer("Keys: W/A/S/D move, Q/E or Ctrl/Space down/up, Shift 4x faster, mouse looks (captured; Escape\n"
                "releases it, a click captures it again). P saves EXR+PNG, C prints the camera as render options,\n"
                "R restarts, 1-9 switch integrator (" + commaSeparated(integratorNames()) + "). Closing the window quits.");
    return [a] { return runView(*a); };
}

}  // namespace tessera::app
