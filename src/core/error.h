#pragma once
/// \file error.h
/// Error types shared by every layer. A user-facing error carries a message that already names the
/// file, the element and the problem; the CLI prints it on one line and exits with code 2.
#include <cstddef>
#include <stdexcept>
#include <string>

namespace tessera {

/// An error caused by the user's input (scene file, command line, image file). Never a bug.
class InputError : public std::runtime_error {
public:
    explicit InputError(const std::string& message) : std::runtime_error(message) {}
};

/// A scene-loading error: "FILE: ELEMENT: PROBLEM", e.g. "box.gltf: meshes[3].primitives[0]: ...".
class SceneError : public InputError {
public:
    SceneError(const std::string& file, const std::string& element, const std::string& problem)
        : InputError(file + ": " + (element.empty() ? std::string() : element + ": ") + problem) {}
};

/// The element part of a SceneError for entry `i` of a scene file's array: "meshes[3]".
inline std::string indexedElement(const char* array, size_t i) { return std::string(array) + "[" + std::to_string(i) + "]"; }

}  // namespace tessera
