// SPDX-License-Identifier: BSD-3-Clause
//
// Internal to the mesh stage (it includes OpenMesh; never include it from a
// public header): the halfedge mesh type, double precision.
#pragma once

// OpenMesh wants its IO header before the mesh kernel.
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

namespace bayon {

struct OmTraits : public OpenMesh::DefaultTraits {
  using Point = OpenMesh::Vec3d;
  using Normal = OpenMesh::Vec3d;
};
using OmMesh = OpenMesh::TriMesh_ArrayKernelT<OmTraits>;

}  // namespace bayon
