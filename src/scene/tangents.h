#pragma once
/// \file tangents.h
/// Per-vertex tangents for normal mapping when a glTF primitive has a normal texture but no TANGENT
/// attribute. The glTF 2.0 specification (3.7.2.1) asks for MikkTSpace tangents; this is an
/// implementation from Mikkelsen's thesis ("Simulation of Wrinkled Surfaces Revisited", 2008,
/// ch. 3 and 4), not from the reference code.
#include "geometry/shapes.h"

namespace tessera {

/// Fills `mesh.tangents` (xyz unit, w = ±1 bitangent sign with B = w · (N × T)) from positions,
/// normals and glTF texcoords[uvSet] (v down the image; MikkTSpace runs on (u, 1 − v), so B points
/// up the image, the +Y of a normal map) in the space they are given in (the glTF loader calls it in object
/// space, before the node transform, as the file's own tangents would be). Needs normals and
/// texcoords[uvSet]. Vertices whose corners fall into different MikkTSpace groups (a UV mirror
/// seam through a shared vertex) are duplicated, so `mesh.triangles` and every per-vertex array
/// may grow. Returns the number of vertices added.
size_t generateMikkTangents(TriangleMesh& mesh, int uvSet);

/// glTF 3.7.2.1: a primitive without NORMAL is flat shaded. Gives every triangle corner its own
/// vertex with the face normal, so that tangents can be generated per face. Triangles whose
/// normal is zero keep a zero normal (the loader drops them as degenerate).
void unweldWithFlatNormals(TriangleMesh& mesh);

}  // namespace tessera
