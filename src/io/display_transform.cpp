#include "io/display_transform.h"

#include <OpenColorIO/OpenColorIO.h>

#include <algorithm>
#include <cstddef>
#include <sstream>
#include <stdexcept>

#include "core/error.h"

namespace OCIO = OCIO_NAMESPACE;

namespace tessera::io {

struct DisplayTransform::Impl {
    OCIO::ConstCPUProcessorRcPtr cpu;
};

namespace {

/// What to call the config in messages: its path, or a name for the embedded one.
std::string configLabel(const std::string& configPath) {
    return configPath.empty() ? std::string("built-in OCIO config") : configPath;
}

OCIO::ConstConfigRcPtr loadConfig(const std::string& configPath) {
    if (configPath.empty()) {
        // Parsed from memory rather than through OCIO::GetCurrentConfig(), which would honour
        // $OCIO and make PNG output depend on the user's environment.
        try {
            std::istringstream text(kOcioConfigText);
            return OCIO::Config::CreateFromStream(text);
        } catch (const OCIO::Exception& e) {
            // The embedded config is validated at build time by ociocheck; failing here is a bug.
            throw std::logic_error(std::string("built-in OCIO config is invalid: ") + e.what());
        }
    }
    try {
        OCIO::ConstConfigRcPtr config = OCIO::Config::CreateFromFile(configPath.c_str());
        config->validate();
        return config;
    } catch (const OCIO::Exception& e) {
        throw InputError(configPath + ": cannot use as an OCIO config: " + e.what());
    }
}

std::string joinQuoted(const std::vector<std::string>& names) {
    std::string out;
    for (const std::string& name : names) out += (out.empty() ? "\"" : ", \"") + name + "\"";
    return out.empty() ? std::string("(none)") : out;
}

std::vector<std::string> displayNames(const OCIO::Config& config) {
    std::vector<std::string> names;
    for (int i = 0; i < config.getNumDisplays(); ++i) names.emplace_back(config.getDisplay(i));
    return names;
}

/// The views of `display`, or InputError naming the displays that do exist.
std::vector<std::string> viewNames(const OCIO::Config& config, const std::string& display,
                                   const std::string& configPath) {
    std::vector<std::string> displays = displayNames(config);
    if (std::find(displays.begin(), displays.end(), display) == displays.end()) {
        throw InputError(configLabel(configPath) + ": unknown display \"" + display +
                         "\"; available displays: " + joinQuoted(displays));
    }
    std::vector<std::string> names;
    for (int i = 0; i < config.getNumViews(display.c_str()); ++i) {
        names.emplace_back(config.getView(display.c_str(), i));
    }
    return names;
}

}  // namespace

DisplayTransform::DisplayTransform(const std::string& display, const std::string& view,
                                   const std::string& configPath) {
    OCIO::ConstConfigRcPtr config = loadConfig(configPath);
    std::vector<std::string> views = viewNames(*config, display, configPath);
    if (std::find(views.begin(), views.end(), view) == views.end()) {
        throw InputError(configLabel(configPath) + ": unknown view \"" + view +
                         "\" for display \"" + display + "\"; available views: " +
                         joinQuoted(views));
    }
    try {
        OCIO::ConstProcessorRcPtr processor = config->getProcessor(
            OCIO::ROLE_SCENE_LINEAR, display.c_str(), view.c_str(), OCIO::TRANSFORM_DIR_FORWARD);
        auto impl = std::make_shared<Impl>();
        impl->cpu = processor->getDefaultCPUProcessor();
        impl_ = std::move(impl);
    } catch (const OCIO::Exception& e) {
        // E.g. a user config without a scene_linear role, or a view whose LUT file is missing.
        throw InputError(configLabel(configPath) + ": cannot build display transform \"" +
                         display + "\" / \"" + view + "\": " + e.what());
    }
}

void DisplayTransform::apply(float* rgba, int width, int height) const {
    if (width <= 0 || height <= 0) return;
    // Described to OCIO as 3-channel RGB pixels 16 bytes apart, so the processor never reads or
    // writes alpha: some ops (4x4 matrices, ranges) would otherwise be free to change it.
    constexpr std::ptrdiff_t kChannelStride = sizeof(float);
    constexpr std::ptrdiff_t kPixelStride = 4 * sizeof(float);
    OCIO::PackedImageDesc image(rgba, width, height, OCIO::CHANNEL_ORDERING_RGB,
                                OCIO::BIT_DEPTH_F32, kChannelStride, kPixelStride,
                                kPixelStride * width);
    impl_->cpu->apply(image);
}

std::vector<std::string> DisplayTransform::displays(const std::string& configPath) {
    return displayNames(*loadConfig(configPath));
}

std::vector<std::string> DisplayTransform::views(const std::string& display,
                                                 const std::string& configPath) {
    return viewNames(*loadConfig(configPath), display, configPath);
}

}  // namespace tessera::io
