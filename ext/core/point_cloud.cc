// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/point_cloud.h"

#include "ext/core/errors.h"

#include <cmath>
#include <stdexcept>

namespace bayon {

const PointAttribute* PointCloud::FindAttribute(const std::string& name) const {
  for (const PointAttribute& attribute : attributes) {
    if (attribute.name == name) return &attribute;
  }
  return nullptr;
}

PointAttribute* PointCloud::FindAttribute(const std::string& name) {
  for (PointAttribute& attribute : attributes) {
    if (attribute.name == name) return &attribute;
  }
  return nullptr;
}

PointAttribute& PointCloud::AddAttribute(const std::string& name,
                                         PlyScalarType type,
                                         double value) {
  PointAttribute* attribute = FindAttribute(name);
  if (attribute == nullptr) {
    attributes.push_back(PointAttribute{name, type, {}});
    attribute = &attributes.back();
  }
  attribute->type = type;
  attribute->values.assign(size(), value);
  return *attribute;
}

namespace {

template <typename T>
void FilterVector(const std::vector<bool>& keep, std::vector<T>* values) {
  if (values->empty()) return;
  size_t out = 0;
  for (size_t i = 0; i < values->size(); ++i) {
    if (keep[i]) (*values)[out++] = (*values)[i];
  }
  values->resize(out);
}

}  // namespace

void PointCloud::Filter(const std::vector<bool>& keep) {
  if (keep.size() != size()) {
    throw std::invalid_argument("PointCloud::Filter: mask size differs");
  }
  FilterVector(keep, &positions);
  FilterVector(keep, &normals);
  FilterVector(keep, &colors);
  for (PointAttribute& attribute : attributes) {
    FilterVector(keep, &attribute.values);
  }
}

void PointCloud::Append(const PointCloud& other) {
  if (other.empty()) return;
  if (empty() && attributes.empty()) {
    *this = other;
    return;
  }
  if (HasNormals() != other.HasNormals() || HasColors() != other.HasColors() ||
      attributes.size() != other.attributes.size()) {
    ThrowInputError("cannot append point clouds with different attributes");
  }
  for (size_t i = 0; i < attributes.size(); ++i) {
    if (attributes[i].name != other.attributes[i].name) {
      ThrowInputError("cannot append point clouds: attribute '",
                      attributes[i].name,
                      "' vs '",
                      other.attributes[i].name,
                      "'");
    }
  }
  positions.insert(
      positions.end(), other.positions.begin(), other.positions.end());
  normals.insert(normals.end(), other.normals.begin(), other.normals.end());
  colors.insert(colors.end(), other.colors.begin(), other.colors.end());
  for (size_t i = 0; i < attributes.size(); ++i) {
    attributes[i].values.insert(attributes[i].values.end(),
                                other.attributes[i].values.begin(),
                                other.attributes[i].values.end());
  }
}

void PointCloud::Check(const std::string& what) const {
  const size_t n = size();
  if (!normals.empty() && normals.size() != n) {
    ThrowInputError(what, ": ", normals.size(), " normals for ", n, " points");
  }
  if (!colors.empty() && colors.size() != n) {
    ThrowInputError(what, ": ", colors.size(), " colours for ", n, " points");
  }
  for (const PointAttribute& attribute : attributes) {
    if (attribute.values.size() != n) {
      ThrowInputError(what,
                      ": attribute '",
                      attribute.name,
                      "' has ",
                      attribute.values.size(),
                      " values for ",
                      n,
                      " points");
    }
  }
  for (size_t i = 0; i < n; ++i) {
    if (!positions[i].allFinite()) {
      ThrowInputError(what,
                      ": point ",
                      i,
                      " has a coordinate that is not a "
                      "finite number");
    }
  }
}

void TriangleMesh::Check(const std::string& what) const {
  vertices.Check(what);
  const int n = static_cast<int>(vertices.size());
  for (size_t f = 0; f < faces.size(); ++f) {
    const Eigen::Vector3i& face = faces[f];
    for (int k = 0; k < 3; ++k) {
      if (face(k) < 0 || face(k) >= n) {
        ThrowInputError(
            what, ": face ", f, " refers to vertex ", face(k), " of ", n);
      }
    }
    if (face(0) == face(1) || face(1) == face(2) || face(0) == face(2)) {
      ThrowInputError(what, ": face ", f, " repeats a vertex");
    }
  }
  if (!face_texcoords.empty() && face_texcoords.size() != faces.size()) {
    ThrowInputError(what,
                    ": ",
                    face_texcoords.size(),
                    " texture coordinate "
                    "triples for ",
                    faces.size(),
                    " faces");
  }
}

}  // namespace bayon
