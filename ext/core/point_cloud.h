// SPDX-License-Identifier: BSD-3-Clause
//
// Point clouds and triangle meshes in memory: plain structs that the dense,
// cloud, mesh, texture and render stages share. Files are PLY
// (ext/colmap/ply_io.h). Object coordinates in metres.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace bayon {

// How a per-point scalar is stored in a PLY file.
enum class PlyScalarType { kUChar, kInt, kUInt, kFloat, kDouble };

// A named per-point value (standard deviations, number of images, master
// image id, interest value, ...), one per point.
struct PointAttribute {
  std::string name;
  PlyScalarType type = PlyScalarType::kFloat;
  std::vector<double> values;
};

struct PointCloud {
  std::vector<Eigen::Vector3d> positions;
  std::vector<Eigen::Vector3f> normals;              // empty or one per point
  std::vector<Eigen::Matrix<uint8_t, 3, 1>> colors;  // empty or one per point
  std::vector<PointAttribute> attributes;            // each one per point

  size_t size() const { return positions.size(); }
  bool empty() const { return positions.empty(); }
  bool HasNormals() const { return !normals.empty(); }
  bool HasColors() const { return !colors.empty(); }

  // The attribute of that name, or nullptr.
  const PointAttribute* FindAttribute(const std::string& name) const;
  PointAttribute* FindAttribute(const std::string& name);
  // Adds (or resets) an attribute filled with `value` for every point.
  PointAttribute& AddAttribute(const std::string& name,
                               PlyScalarType type,
                               double value = 0.0);

  // Keeps the points whose mask entry is true, in every per-point array.
  void Filter(const std::vector<bool>& keep);
  // Appends another cloud with the same layout (same optional arrays and
  // attribute names); throws InputError otherwise.
  void Append(const PointCloud& other);

  // Throws InputError naming `what` if array sizes disagree or a coordinate
  // is not finite.
  void Check(const std::string& what) const;
};

// A triangle mesh: its vertices are a point cloud (with normals, colours and
// attributes), faces index them counter-clockwise seen from outside.
struct TriangleMesh {
  PointCloud vertices;
  std::vector<Eigen::Vector3i> faces;
  // Optional texture coordinates per face corner (u right, v up, in [0, 1]),
  // one entry per face, as MeshLab's `texcoord` face property.
  std::vector<std::array<Eigen::Vector2f, 3>> face_texcoords;

  size_t NumVertices() const { return vertices.size(); }
  size_t NumFaces() const { return faces.size(); }
  bool HasTexcoords() const { return !face_texcoords.empty(); }

  // Throws InputError if a face refers to a missing vertex, repeats a vertex
  // or the texture coordinates do not match the faces.
  void Check(const std::string& what) const;
};

}  // namespace bayon
