#pragma once
/// \file version.h
/// Tessera's version and the git revision it was configured from (recorded in output metadata).
namespace tessera {
const char* versionString();
const char* gitRevision();
}  // namespace tessera
