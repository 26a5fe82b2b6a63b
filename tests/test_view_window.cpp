// `tessera view` in a real window: an Xvfb server of our own (on a display it picks itself with
// -displayfd), the viewer driven by xdotool key and mouse events and by a --script, and the effects
// checked from outside: the camera moved by speed × held time, accumulation restarted (spp dropped),
// the mouse turned the view, the image P saved equals a batch render of the printed camera bit for
// bit, and the window's own pixels (captured with xwd) equal that image through the display
// transform. Skips, saying why, without Xvfb/xdotool/xwd; under CI=true their absence is a failure
// (tools/bootstrap.sh installs them in the `build` group that tools/test.sh installs).
#include <gtest/gtest.h>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <thread>

#include "io/display_transform.h"
#include "io/image_output.h"
#include "test_helpers.h"

extern char** environ;

using namespace tessera;

namespace {

using Clock = std::chrono::steady_clock;

bool onPath(const std::string& program) {
    return std::system(("command -v " + program + " >/dev/null 2>&1").c_str()) == 0;
}

/// Skips (or, in CI, fails) when a tool the window test needs is missing.
#define REQUIRE_WINDOW_TOOLS()                                                                                            \
    do {                                                                                                                  \
        for (const char* tool : {"Xvfb", "xdotool", "xwd"})                                                              \
            if (!onPath(tool)) {                                                                                          \
                std::string why = std::string(tool) + " is not installed (Debian: xvfb, xdotool, x11-apps; "              \
                                  "tools/bootstrap.sh --install build)";                                                 \
                if (std::getenv("CI")) FAIL() << why;                                                                     \
                GTEST_SKIP() << why;                                                                                      \
            }                                                                                                             \
    } while (0)

std::string slurp(const std::filesystem::path& p) {
    std::ifstream f(p, std::ios::binary);
    std::ostringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

/// A child process we started, ended by its own pid only.
class Child {
public:
    /// argv[0] is looked up on PATH; stdout/stderr go to the files given (empty: inherited). `fd3`
    /// (>= 0) becomes the child's descriptor 3.
    Child(const std::vector<std::string>& argv, const std::string& out, const std::string& err, int fd3 = -1) {
        posix_spawn_file_actions_t fa;
        posix_spawn_file_actions_init(&fa);
        if (!out.empty()) posix_spawn_file_actions_addopen(&fa, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (!err.empty()) posix_spawn_file_actions_addopen(&fa, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (fd3 >= 0) posix_spawn_file_actions_adddup2(&fa, fd3, 3);
        std::vector<char*> args;
        for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
        args.push_back(nullptr);
        if (posix_spawnp(&pid_, args[0], &fa, nullptr, args.data(), environ) != 0) pid_ = -1;
        posix_spawn_file_actions_destroy(&fa);
    }
    ~Child() { stop(SIGKILL); }
    Child(const Child&) = delete;
    Child& operator=(const Child&) = delete;
    bool started() const { return pid_ > 0; }
    pid_t pid() const { return pid_; }

    /// Waits up to `seconds` for the exit; the exit status, or -1 on a timeout or a signal.
    int wait(double seconds) {
        auto end = Clock::now() + std::chrono::duration<double>(seconds);
        while (pid_ > 0) {
            int status = 0;
            pid_t r = waitpid(pid_, &status, WNOHANG);
            if (r == pid_) {
                pid_ = -1;
                return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
            }
            if (Clock::now() > end) return -1;
            std::this_thread::sleep_for(std::chrono::milliseconds(20));
        }
        return -1;
    }
    void signal(int sig) {
        if (pid_ > 0) kill(pid_, sig);
    }
    void stop(int sig) {
        if (pid_ <= 0) return;
        kill(pid_, sig);
        waitpid(pid_, nullptr, 0);
        pid_ = -1;
    }

private:
    pid_t pid_ = -1;
};

/// Our own Xvfb: -displayfd makes it pick a free display and write its number to our pipe (no race
/// with other servers on this machine); the destructor ends exactly this process.
class Xvfb {
public:
    Xvfb() {
        int fds[2];
        if (pipe(fds) != 0) return;
        server_ = std::make_unique<Child>(std::vector<std::string>{"Xvfb", "-displayfd", "3", "-screen", "0", "800x600x24", "-nolisten", "tcp"},
                                          "/dev/null", "/dev/null", fds[1]);
        close(fds[1]);
        std::string number;
        pollfd p{fds[0], POLLIN, 0};
        auto end = Clock::now() + std::chrono::seconds(15);
        while (Clock::now() < end && number.find('\n') == std::string::npos) {
            if (poll(&p, 1, 200) > 0) {
                char buf[16];
                ssize_t n = read(fds[0], buf, sizeof buf);
                if (n <= 0) break;
                number.append(buf, size_t(n));
            }
        }
        close(fds[0]);
        if (number.find('\n') != std::string::npos) display_ = ":" + number.substr(0, number.find('\n'));
    }
    ~Xvfb() {
        if (server_) server_->stop(SIGTERM);
    }
    const std::string& display() const { return display_; }  ///< empty: the server did not start

private:
    std::unique_ptr<Child> server_;
    std::string display_;
};

/// Runs a shell command line with DISPLAY set; its exit status.
int onDisplay(const std::string& display, const std::string& command) {
    return std::system(("DISPLAY=" + display + " " + command).c_str());
}

std::string onDisplayOutput(const std::string& display, const std::string& command) {
    std::string out;
    if (FILE* f = popen(("DISPLAY=" + display + " " + command).c_str(), "r")) {
        char buf[256];
        while (fgets(buf, sizeof buf, f)) out += buf;
        pclose(f);
    }
    return out;
}

/// The key=value pairs of the last "view-status" line of `text` (empty if none).
std::map<std::string, std::string> lastStatus(const std::string& text) {
    std::map<std::string, std::string> kv;
    size_t at = text.rfind("view-status ");
    if (at == std::string::npos) return kv;
    std::istringstream line(text.substr(at + 12, text.find('\n', at) - at - 12));
    for (std::string item; line >> item;)
        if (size_t eq = item.find('='); eq != std::string::npos) kv[item.substr(0, eq)] = item.substr(eq + 1);
    return kv;
}
double num(const std::map<std::string, std::string>& kv, const std::string& key) {
    auto it = kv.find(key);
    return it == kv.end() ? std::nan("") : std::strtod(it->second.c_str(), nullptr);
}
size_t countOf(const std::string& text, const std::string& what) {
    size_t n = 0;
    for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
}

/// An X window dump (xwd, ZPixmap, 24/32 bits per pixel) as packed 8-bit RGB.
bool readXwd(const std::string& path, int& width, int& height, std::vector<uint8_t>& rgb) {
    std::string d = slurp(path);
    if (d.size() < 100) return false;
    auto be32 = [&](size_t i) {
        return uint32_t(uint8_t(d[i])) << 24 | uint32_t(uint8_t(d[i + 1])) << 16 | uint32_t(uint8_t(d[i + 2])) << 8 | uint32_t(uint8_t(d[i + 3]));
    };
    uint32_t headerSize = be32(0), format = be32(8), byteOrder = be32(28), bpp = be32(44), bytesPerLine = be32(48);
    uint32_t masks[3] = {be32(56), be32(60), be32(64)}, ncolors = be32(76);
    width = int(be32(16));
    height = int(be32(20));
    if (format != 2 || (bpp != 32 && bpp != 24)) return false;
    size_t data = size_t(headerSize) + size_t(ncolors) * 12;
    if (d.size() < data + size_t(bytesPerLine) * size_t(height)) return false;
    rgb.assign(size_t(width) * size_t(height) * 3, 0);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            size_t p = data + size_t(y) * bytesPerLine + size_t(x) * (bpp / 8);
            uint32_t v = 0;
            for (uint32_t b = 0; b < bpp / 8; ++b) {
                uint32_t byte = uint8_t(d[p + b]);
                v |= byteOrder == 0 ? byte << (8 * b) : byte << (8 * (bpp / 8 - 1 - b));
            }
            for (int c = 0; c < 3; ++c) {
                uint32_t m = masks[c], shift = 0;
                if (m == 0) return false;
                while (!((m >> shift) & 1u)) ++shift;
                rgb[(size_t(y) * width + x) * 3 + c] = uint8_t((v & m) >> shift);
            }
        }
    return true;
}

const std::string kScene = "scenes/sphere-cornell/sphere-cornell.gltf";

/// The environment a viewer child runs with: our display; leaks inside libX11/SDL are not ours, so
/// LeakSanitizer (asan builds) is off for this process alone, every other check stays on.
std::vector<std::string> viewerCommand(const std::string& display, std::vector<std::string> args) {
    const char* asan = std::getenv("ASAN_OPTIONS");
    std::vector<std::string> cmd = {"env", "DISPLAY=" + display,
                                    "ASAN_OPTIONS=" + std::string(asan ? asan : "") + ":detect_leaks=0", TESSERA_BINARY, "view"};
    cmd.insert(cmd.end(), args.begin(), args.end());
    return cmd;
}

}  // namespace

#if defined(__SANITIZE_THREAD__)
#define TESSERA_SKIP_UNDER_TSAN() GTEST_SKIP() << "SDL and libX11 are not built for ThreadSanitizer; PreviewSession.* covers the preview's threads"
#else
#define TESSERA_SKIP_UNDER_TSAN() (void)0
#endif

TEST(ViewWindow, KeysAndMouseMoveTheCameraRestartAndThePixelsMatchABatchRender) {
    TESSERA_SKIP_UNDER_TSAN();
    REQUIRE_WINDOW_TOOLS();
    Xvfb x;
    ASSERT_FALSE(x.display().empty()) << "Xvfb did not report a display";
    auto dir = test::tempDir("view-window");
    const uint32_t sppLimit = 8;
    Child viewer(viewerCommand(x.display(), {test::sourcePath(kScene), "--resolution", "160x120", "--spp", std::to_string(sppLimit),
                                             "--threads", "2", "--exit-after", "60", "--print-camera", "-o", (dir / "view.exr").string()}),
                 (dir / "out.txt").string(), (dir / "err.txt").string());
    ASSERT_TRUE(viewer.started());
    std::string wid = onDisplayOutput(x.display(), "timeout 20 xdotool search --sync --name 'tessera view'");
    wid = wid.substr(0, wid.find('\n'));
    ASSERT_FALSE(wid.empty()) << "no window appeared; stderr: " << slurp(dir / "err.txt");
    ASSERT_EQ(onDisplay(x.display(), "xdotool windowfocus --sync " + wid), 0);
    auto status = [&] { return lastStatus(slurp(dir / "out.txt")); };
    auto pressC = [&] {
        size_t before = countOf(slurp(dir / "out.txt"), "view-status");
        onDisplay(x.display(), "xdotool key c");
        for (int i = 0; i < 200 && countOf(slurp(dir / "out.txt"), "view-status") == before; ++i)
            std::this_thread::sleep_for(std::chrono::milliseconds(20));
        return status();
    };

    // Accumulating: wait for at least 2 spp.
    std::map<std::string, std::string> s1;
    for (int i = 0; i < 100 && !(num(s1, "spp") >= 2); ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
        s1 = pressC();
    }
    ASSERT_GE(num(s1, "spp"), 2) << slurp(dir / "out.txt") << slurp(dir / "err.txt");

    // W held for half a second: forward by speed × held time, accumulation restarted.
    onDisplay(x.display(), "xdotool keydown w sleep 0.5 keyup w");
    std::map<std::string, std::string> s2 = pressC();
    double speed = num(s2, "speed"), travelled = num(s2, "travelled");
    EXPECT_GT(speed, 0.0);
    EXPECT_GT(travelled, 0.4 * speed) << "W held ~0.5 s";
    EXPECT_LT(travelled, 0.9 * speed) << "W held ~0.5 s (xdotool's own delays allowed for)";
    EXPECT_LT(num(s2, "spp"), num(s1, "spp")) << "accumulation restarted: spp dropped";
    EXPECT_GE(num(s2, "reduced_frames"), 1) << "reduced-resolution frames while moving";
    // The render thread counts the new accumulation when it starts it (after the reduced frame in flight).
    for (int i = 0; i < 50 && !(num(s2, "restarts") > num(s1, "restarts")); ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
        s2 = pressC();
    }
    EXPECT_GT(num(s2, "restarts"), num(s1, "restarts"));

    // The mouse (captured: relative motion) turns the view: 40 px right = 40 × 0.0025 rad of yaw.
    onDisplay(x.display(), "xdotool mousemove_relative -- 40 0");
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    std::map<std::string, std::string> s3 = pressC();
    EXPECT_NEAR(num(s3, "yaw") - num(s2, "yaw"), 0.1, 0.03);

    // P once the refinement has reached the limit: the saved image has sppLimit spp.
    std::string out;
    for (int i = 0; i < 100 && out.find("(" + std::to_string(sppLimit) + " spp)") == std::string::npos; ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(150));
        onDisplay(x.display(), "xdotool key p");
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
        out = slurp(dir / "out.txt");
    }
    ASSERT_NE(out.find("(" + std::to_string(sppLimit) + " spp)"), std::string::npos) << out << slurp(dir / "err.txt");
    std::this_thread::sleep_for(std::chrono::milliseconds(200));  // the last frame is on screen (shown within 50 ms)
    ASSERT_EQ(onDisplay(x.display(), "xwd -silent -id " + wid + " -out " + (dir / "window.xwd").string()), 0);

    // Closing (SIGINT arrives as SDL_QUIT, like the window's close button) exits cleanly and prints the camera.
    viewer.signal(SIGINT);
    EXPECT_EQ(viewer.wait(10.0), 0) << slurp(dir / "err.txt");
    out = slurp(dir / "out.txt");
    size_t cmdAt = out.rfind("tessera render ");
    ASSERT_NE(cmdAt, std::string::npos) << out;
    std::string renderArgs = out.substr(cmdAt + std::string("tessera render ").size());
    renderArgs = renderArgs.substr(0, renderArgs.find('\n'));

    // The batch render of the printed camera: the same bits (ptnee, same seed and spp).
    std::string batch = (dir / "batch.exr").string();
    ASSERT_EQ(std::system((std::string(TESSERA_BINARY) + " render " + renderArgs + " --threads 1 --quiet -o " + batch).c_str()), 0) << renderArgs;
    io::Image viewed = io::readImage((dir / "view.exr").string()), batchImage = io::readImage(batch);
    ASSERT_EQ(viewed.width, 160);
    ASSERT_EQ(batchImage.width, 160);
    EXPECT_EQ(viewed.rgba, batchImage.rgba) << "the saved preview differs from `tessera render " << renderArgs << "`";
    for (const auto& [k, v] : viewed.metadata) {
        if (k == "tessera:spp") {
            EXPECT_EQ(v, std::to_string(sppLimit));
        }
    }

    // The window shows exactly that image through the PNG's display transform.
    int w = 0, h = 0;
    std::vector<uint8_t> window;
    ASSERT_TRUE(readXwd((dir / "window.xwd").string(), w, h, window));
    ASSERT_EQ(w, 160);
    ASSERT_EQ(h, 120);
    std::vector<uint8_t> expected = io::displayRgb8(160, 120, batchImage.rgba.data(), io::DisplayTransform("sRGB", "Standard"));
    size_t differing = 0;
    for (size_t i = 0; i < expected.size(); ++i) differing += window[i] != expected[i];
    EXPECT_EQ(differing, 0u) << "window pixels that differ from the display-transformed batch render";
}

TEST(ViewWindow, AScriptMovesExactlyAndClosingMidPassExitsCleanly) {
    TESSERA_SKIP_UNDER_TSAN();
    REQUIRE_WINDOW_TOOLS();
    Xvfb x;
    ASSERT_FALSE(x.display().empty()) << "Xvfb did not report a display";
    auto dir = test::tempDir("view-script");
    std::ofstream(dir / "walk.txt") << "# forward 0.5 s, then look right and up, quit while refining\n"
                                       "0.3 down w\n0.8 up w\n0.9 look 40 -20\n1.0 down shift\n1.0 down a\n1.25 up a\n1.3 up shift\n"
                                       "2.5 quit\n";
    auto t0 = Clock::now();
    // 640x480 without a spp limit: passes are running when the script quits.
    Child viewer(viewerCommand(x.display(), {test::sourcePath(kScene), "--resolution", "640x480", "--threads", "2", "--script",
                                             (dir / "walk.txt").string(), "--print-camera"}),
                 (dir / "out.txt").string(), (dir / "err.txt").string());
    ASSERT_TRUE(viewer.started());
    int rc = viewer.wait(60.0);
    double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    ASSERT_EQ(rc, 0) << slurp(dir / "err.txt");
    auto s = lastStatus(slurp(dir / "out.txt"));
    double speed = num(s, "speed");
    // Scripted events carry their own times: 0.5 s forward + 0.25 s left at 4x.
    EXPECT_NEAR(num(s, "travelled"), speed * (0.5 + 0.25 * 4.0), 1e-4 * speed);
    EXPECT_NEAR(num(s, "yaw"), 40 * 0.0025, 1e-5);
    EXPECT_NEAR(num(s, "pitch"), 20 * 0.0025, 1e-5);
    EXPECT_GE(num(s, "restarts"), 2);
    // Load + 2.5 s of script + a clean close within a tile (a 640x480 pass would take longer).
    EXPECT_LT(seconds, 20.0);
}

TEST(ViewWindow, WithoutADisplayItSaysSoAndSuggestsRender) {
    TESSERA_SKIP_UNDER_TSAN();
    auto dir = test::tempDir("view-nodisplay");
    std::string cmd = "env -u DISPLAY -u WAYLAND_DISPLAY ASAN_OPTIONS=detect_leaks=0 " + std::string(TESSERA_BINARY) + " view " +
                      test::sourcePath(kScene) + " --exit-after 1 2> " + (dir / "err.txt").string();
    int status = std::system(cmd.c_str());
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 2);
    std::string err = slurp(dir / "err.txt");
    EXPECT_NE(err.find("needs a display"), std::string::npos) << err;
    EXPECT_NE(err.find("tessera render"), std::string::npos) << err;
    EXPECT_EQ(countOf(err, "\n"), 1u) << "one line: " << err;
}
