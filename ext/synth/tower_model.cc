// SPDX-License-Identifier: BSD-3-Clause
#include "ext/synth/tower_model.h"

#include "ext/core/errors.h"
#include "ext/core/parallel.h"
#include "ext/synth/tower_noise.h"
#include "ext/targets/coded_targets.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace bayon {

void TowerOptions::Check() const {
  CheckOption(width_m > 0.5, "width_m", "> 0.5", width_m);
  CheckOption(height_m > 1.0, "height_m", "> 1", height_m);
  CheckOption(relief_depth_m >= 0 && relief_depth_m <= 0.25 * width_m,
              "relief_depth_m",
              "in [0, width_m / 4]",
              relief_depth_m);
  CheckOption(
      num_tiers >= 1 && num_tiers <= 6, "num_tiers", "in [1, 6]", num_tiers);
  CheckOption(platform_width_m >= width_m + 1.0,
              "platform_width_m",
              ">= width_m + 1",
              platform_width_m);
  CheckOption(platform_height_m >= 0.2,
              "platform_height_m",
              ">= 0.2",
              platform_height_m);
  CheckOption(mesh_spacing_m >= 0.002 && mesh_spacing_m <= 0.2,
              "mesh_spacing_m",
              "in [0.002, 0.2]",
              mesh_spacing_m);
  CheckOption(texel_size_m >= 0.0005 && texel_size_m <= 0.05,
              "texel_size_m",
              "in [0.0005, 0.05]",
              texel_size_m);
  CheckOption(ground_texel_size_m >= texel_size_m,
              "ground_texel_size_m",
              ">= texel_size_m",
              ground_texel_size_m);
  CheckOption(ground_size_m >= platform_width_m + 4,
              "ground_size_m",
              ">= platform_width_m + 4",
              ground_size_m);
  CheckOption(bar_target_distance_m >= 0.3 && bar_target_distance_m <= 3,
              "bar_target_distance_m",
              "in [0.3, 3]",
              bar_target_distance_m);
  // The default dictionary's codes (aruco_4x4_50).
  CheckOption(num_coded_targets >= 0 &&
                  num_coded_targets <= CodedTargetDictionarySize(
                                           CodedTargetOptions().dictionary),
              "num_coded_targets",
              "in [0, the number of codes, 50]",
              num_coded_targets);
  CheckOption(coded_target_side_m >= 0.05 && coded_target_side_m <= 0.5,
              "coded_target_side_m",
              "in [0.05, 0.5]",
              coded_target_side_m);
}

namespace {

// ---------------------------------------------------------------------------
// Surfaces of the tower as displaced bilinear patches.

enum class Kind {
  kWall,          // a tier's body, with a face on it
  kBand,          // cornice or base moulding with an ornament band
  kFinial,        // lotus-bud tiers on top
  kLedge,         // horizontal ring between two prisms
  kPlatformWall,  // sides of the platform steps
  kPlatformTop,   // the paved top of the platform step under the tower
  kBar,           // levelling staff
  kGround,
};

// A flat spot kept for a target plate, in patch metres.
struct FlatSite {
  double u = 0, v = 0, radius = 0;
};

struct FaceRelief {
  bool present = false;
  double center_u = 0, center_v = 0;  // patch metres
  double half_width = 0, half_height = 0;
  double depth = 0;
};

struct Patch {
  // Corners: s runs c00 -> c10 (left to right seen from outside), t runs
  // c00 -> c01 (bottom to top for walls, outer to inner for up-facing
  // ledges). The patch's outward normal is (c10 - c00) x (c01 - c00).
  Eigen::Vector3d c00, c10, c01, c11;
  int ns = 1, nt = 1;
  Kind kind = Kind::kWall;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double len_s = 1, len_t = 1;  // metres along the bottom and left edges
  // Pattern coordinates: the perimeter position at s = 0 (continuous
  // around the tower) and the world z at t = 0, for vertical patches.
  double perimeter0 = 0;
  double z0 = 0;
  int band_index = 0;  // ornament style of bands and finial tiers
  FaceRelief face;
  std::vector<FlatSite> flat_sites;
  // Displacement is faded to zero over this margin at the patch edges, so
  // that neighbouring patches meet without a gap.
  double edge_margin = 0.04;
  // The patch's texture chart in the atlas (texels), with `pad` texels of
  // continued texture around it for filtering.
  double texel = 0.003;
  int chart_x = 0, chart_y = 0, chart_w = 0, chart_h = 0, pad = 4;

  Eigen::Vector3d Base(double s, double t) const {
    return (1 - s) * (1 - t) * c00 + s * (1 - t) * c10 + (1 - s) * t * c01 +
           s * t * c11;
  }
  bool IsVertical() const { return std::abs(normal.z()) < 0.5; }
};

// Masonry courses and blocks on a vertical surface, from the perimeter
// coordinate and the height.
struct Block {
  int64_t course = 0;
  int64_t index = 0;
  double joint_distance = 1;        // metres to the nearest joint
  double local_x = 0, local_y = 0;  // metres from the block's lower left
  double length = 1, height = 1;
};

class Stone {
 public:
  Stone(uint32_t seed, double max_height) : seed_(seed) {
    double z = -0.05;
    int64_t k = 0;
    while (z < max_height + 1) {
      course_z_.push_back(z);
      z += 0.30 + 0.16 * Hash01(k++, 7, seed_);
    }
    course_z_.push_back(z);
  }

  Block Masonry(double a, double z, double scale) const {
    Block block;
    const auto it =
        std::upper_bound(course_z_.begin(), course_z_.end(), z / scale);
    const int64_t k =
        std::clamp<int64_t>(static_cast<int64_t>(it - course_z_.begin()) - 1,
                            0,
                            static_cast<int64_t>(course_z_.size()) - 2);
    const double z_low = course_z_[k] * scale,
                 z_high = course_z_[k + 1] * scale;
    block.course = k;
    const double length = scale * (0.45 + 0.4 * Hash01(k, 1, seed_));
    const double offset = length * Hash01(k, 2, seed_);
    auto boundary = [&](int64_t i) {
      return offset + i * length +
             (Hash01(k, i, 3, seed_) - 0.5) * 0.35 * length;
    };
    int64_t i = static_cast<int64_t>(std::floor((a - offset) / length));
    while (a < boundary(i)) --i;
    while (a >= boundary(i + 1)) ++i;
    block.index = i;
    const double left = boundary(i), right = boundary(i + 1);
    block.local_x = a - left;
    block.local_y = z - z_low;
    block.length = right - left;
    block.height = z_high - z_low;
    block.joint_distance =
        std::min({a - left, right - a, z - z_low, z_high - z});
    return block;
  }

  // Paving slabs on a horizontal surface.
  Block Paving(double x, double y) const {
    Block block;
    const double size_y = 0.7;
    const int64_t row = static_cast<int64_t>(std::floor(y / size_y));
    const double length = 0.6 + 0.35 * Hash01(row, 11, seed_);
    const double offset = length * Hash01(row, 12, seed_);
    const int64_t i = static_cast<int64_t>(std::floor((x - offset) / length));
    const double left = offset + i * length;
    block.course = row + 100000;
    block.index = i;
    block.local_x = x - left;
    block.local_y = y - row * size_y;
    block.length = length;
    block.height = size_y;
    block.joint_distance = std::min({block.local_x,
                                     length - block.local_x,
                                     block.local_y,
                                     size_y - block.local_y});
    return block;
  }

  uint32_t seed() const { return seed_; }

 private:
  uint32_t seed_;
  std::vector<double> course_z_;  // course boundaries at scale 1
};

// Gaussian bump in two normalised coordinates.
double Bump(double x, double y, double sx, double sy) {
  return std::exp(-0.5 * (x * x / (sx * sx) + y * y / (sy * sy)));
}

// The carved face in normalised face coordinates: a to the right, b up,
// both in [-1, 1] over the face; returns the relief height in units of the
// relief depth. Stylised after the Bayon faces: broad forehead under a
// diadem and a crown, closed eyes under arched brows, a broad nose, the
// smile, long ear lobes.
double FaceShape(double a, double b) {
  const double abs_a = std::abs(a);
  double d = 0;
  // The head: an egg, broad at the brow, narrower at the chin, flat-fronted.
  const double width = 0.86 * (1.0 - 0.16 * std::max(0.0, -b));
  const double qa = a / width, qb = (b + 0.05) / 0.98;
  const double r2 = qa * qa + qb * qb;
  if (r2 < 1) d += 0.50 * std::pow(1 - r2, 0.3);
  // Cheeks and chin.
  d += 0.10 * Bump(abs_a - 0.38, b + 0.14, 0.15, 0.17);
  d += 0.07 * Bump(a, b + 0.74, 0.17, 0.09);
  // Brows: arched ridges.
  if (abs_a > 0.05 && abs_a < 0.68) {
    const double arch = 0.29 + 0.06 * std::cos(M_PI * (abs_a - 0.36) / 0.62);
    d += 0.07 * Gaussian(b - arch, 0.035) * SmoothStep(0.05, 0.12, abs_a) *
         SmoothStep(0.68, 0.55, abs_a);
  }
  // Eyes: sockets, bulging lids and the line of the closed lids.
  {
    const double ea = (abs_a - 0.33) / 0.19, eb = (b - 0.14) / 0.065;
    const double e = ea * ea + eb * eb;
    d -= 0.06 * Bump(ea, eb, 0.9, 1.3);
    if (e < 1) d += 0.05 * std::sqrt(1 - e);
    const double lid_line = 0.125 - 0.025 * ea * ea;
    if (std::abs(ea) < 1.05) {
      d -= 0.045 * Gaussian(b - lid_line, 0.010) *
           SmoothStep(1.05, 0.8, std::abs(ea));
    }
  }
  // Nose: a ridge widening from the bridge to the tip, and the nostrils.
  {
    const double tn = std::clamp((0.27 - b) / 0.45, 0.0, 1.0);
    const double half = 0.05 + 0.085 * tn;
    const double height = 0.28 * (0.35 + 0.65 * tn) *
                          SmoothStep(-0.30, -0.17, b) *
                          SmoothStep(0.36, 0.24, b);
    d += height * Gaussian(a, half);
    d += 0.06 * Bump(abs_a - 0.10, b + 0.17, 0.045, 0.04);
    d -= 0.07 * Bump(abs_a - 0.065, b + 0.205, 0.025, 0.016);
  }
  // The smile: lips along a curve rising to the corners, and the slit.
  if (abs_a < 0.42) {
    const double corners = SmoothStep(0.42, 0.30, abs_a);
    const double line = -0.45 + 0.24 * a * a;
    d += corners * (0.08 * Gaussian(b - line - 0.035, 0.028) +
                    0.09 * Gaussian(b - line + 0.045, 0.033) -
                    0.06 * Gaussian(b - line, 0.009));
  }
  // Ears: long lobes with a groove along the rim.
  {
    const double ea = (abs_a - 0.96) / 0.12, eb = (b + 0.16) / 0.42;
    const double e = std::sqrt(ea * ea + eb * eb);
    if (e < 1) d += 0.16 * std::sqrt(1 - e * e);
    d -= 0.04 * Gaussian(e - 0.62, 0.09) * (e < 1 ? 1.0 : 0.0);
  }
  // Diadem: a band of beads across the forehead.
  if (b > 0.50 && b < 0.68 && abs_a < 0.86) {
    const double band = SmoothStep(0.50, 0.54, b) * SmoothStep(0.68, 0.64, b) *
                        SmoothStep(0.86, 0.78, abs_a);
    const double beads = 0.5 + 0.5 * std::cos(2 * M_PI * a * 9);
    d += band * (0.10 + 0.05 * beads);
  }
  // Crown: tapering tiers of petal-shaped flames above the diadem.
  if (b > 0.66 && b < 1.10) {
    const double tb = (b - 0.66) / 0.44;
    const double half = 0.74 * (1 - 0.55 * tb);
    if (abs_a < half) {
      const double phase = std::fmod(std::abs(a / 0.16 + 10.5), 1.0) - 0.5;
      const double row = std::fmod(tb * 3.0, 1.0);
      const double petal = std::max(
          0.0,
          1 - std::pow(phase / 0.45, 2) - std::pow((row - 0.45) / 0.55, 2));
      d += SmoothStep(half, half - 0.06, abs_a) * (0.22 - 0.1 * tb) *
           (0.6 + 0.4 * std::sqrt(petal));
    }
  }
  return d;
}

// A raised ornament band (cornice, base moulding): v in [0, 1] across the
// band, x along it in metres; height in metres.
double BandOrnament(double x, double v, int style, double scale) {
  double d = 0.02 * scale * std::sin(M_PI * std::clamp(v, 0.0, 1.0));
  if (style % 2 == 0) {
    // Lotus petals with a central rib, beads along the top.
    const double period = 0.16 * scale;
    const double phase = std::fmod(std::abs(x / period + 100.5), 1.0) - 0.5;
    const double e = std::pow(phase / 0.44, 2) + std::pow((v - 0.42) / 0.45, 2);
    if (e < 1) d += 0.015 * scale * std::sqrt(1 - e);
    d += 0.004 * scale * Gaussian(phase, 0.03) * (e < 1 ? 1.0 : 0.0);
    if (v > 0.82) {
      const double bead_phase =
          std::fmod(std::abs(x / (0.05 * scale) + 100.5), 1.0) - 0.5;
      const double r = std::hypot(bead_phase, (v - 0.91) / 0.09 * 0.5);
      if (r < 0.45) d += 0.008 * scale * std::sqrt(1 - r * r / 0.2025);
    }
  } else {
    // Rosettes in a row between two fillets.
    const double period = 0.22 * scale;
    const double phase = std::fmod(std::abs(x / period + 100.5), 1.0) - 0.5;
    const double dx = phase * period, dy = (v - 0.5) * 0.6 * period;
    const double r = std::hypot(dx, dy) / (0.45 * period);
    const double angle = std::atan2(dy, dx);
    if (r < 1) {
      d += 0.014 * scale * (1 - r * r) * (0.7 + 0.3 * std::cos(8 * angle));
    }
    d += 0.006 * scale * (Gaussian(v - 0.06, 0.04) + Gaussian(v - 0.94, 0.04));
  }
  return d;
}

// Wall decoration beside the face: corner pilasters and sunken panels with
// scrollwork. u, v in patch metres.
double WallDecoration(const Patch& patch, double u, double v) {
  const double len = patch.len_s, height = patch.len_t;
  double d = 0;
  const double pilaster = 0.07 * len;
  const double corner = std::min(u, len - u);
  if (corner < pilaster) {
    d += 0.02 * SmoothStep(pilaster, pilaster - 0.02, corner);
    const double capital = std::min(v, height - v);
    d += 0.012 * SmoothStep(0.12, 0.08, capital);
  }
  if (patch.face.present) {
    const double face_edge =
        patch.face.half_width * 1.12 + 0.04;  // ears included
    const double du = std::abs(u - patch.face.center_u);
    const double inner = face_edge, outer = 0.5 * len - pilaster - 0.05;
    if (du > inner && du < outer && v > 0.12 && v < height - 0.12) {
      const double edge =
          std::min({du - inner, outer - du, v - 0.12, height - 0.12 - v});
      d -= 0.012 * SmoothStep(0.0, 0.015, edge);
      const double x = du - inner, y = v;
      const double scroll =
          std::sin(2 * M_PI * x / 0.15 + 1.6 * std::sin(2 * M_PI * y / 0.34));
      d += 0.009 * SmoothStep(0.55, 0.9, std::abs(scroll)) *
           SmoothStep(0.0, 0.03, edge);
    }
  }
  return d;
}

class TowerBuilder {
 public:
  explicit TowerBuilder(const TowerOptions& options)
      : options_(options),
        stone_(options.seed, options.platform_height_m + options.height_m) {}

  TowerModel Build();

 private:
  struct Prism {
    double half = 1, z0 = 0, z1 = 1;
    Kind kind = Kind::kWall;
    int tier = -1;
    int band_index = 0;
  };

  void PlanPrisms();
  void AddPrismWalls(const Prism& prism, double* perimeter0);
  void AddRing(const Prism& lower, const Prism& upper);
  void PlanTargets();
  void PlanCodedTargets();
  void PackCharts(int* atlas_width, int* atlas_height);
  double GeometricDisplacement(const Patch& patch, double s, double t) const;
  double FineDisplacement(const Patch& patch, double s, double t) const;
  Eigen::Vector3d Albedo(const Patch& patch,
                         double s,
                         double t,
                         double cavity) const;
  void DrawChart(const Patch& patch, cv::Mat* atlas) const;
  void MeshPatch(const Patch& patch, TriangleMesh* mesh) const;
  void AddFans(TriangleMesh* mesh) const;
  void AddTargetPlates(TowerModel* model, cv::Mat* atlas);
  void AddGround(TriangleMesh* mesh, cv::Mat* atlas) const;

  const TowerOptions& options_;
  Stone stone_;
  std::vector<Prism> prisms_;
  std::vector<Patch> patches_;
  int num_side_ = 0;  // subdivisions along every prism side
  // Charts drawn by hand: target plates and the ground.
  struct Chart {
    int x = 0, y = 0, w = 0, h = 0;
  };
  std::vector<Chart> extra_charts_;
  std::vector<ControlTarget> targets_;
  Eigen::Vector3d bar_base_ = Eigen::Vector3d::Zero();
  double bar_half_ = 0.02, bar_height_ = 2.3;
  Chart ground_chart_, fan_chart_, bar_chart_;
  std::vector<Chart> target_charts_;
};

void TowerBuilder::PlanPrisms() {
  const TowerOptions& o = options_;
  const double w = o.width_m, h = o.height_m;
  const double half_platform = 0.5 * o.platform_width_m;
  const double step = o.platform_height_m / 2;
  prisms_.push_back({half_platform, 0, step, Kind::kPlatformWall, -1, 0});
  prisms_.push_back({half_platform - 0.3,
                     step,
                     o.platform_height_m,
                     Kind::kPlatformWall,
                     -1,
                     1});
  double z = o.platform_height_m;
  // Heights: base moulding, tiers with cornices, finial (fractions of h).
  const double moulding = 0.045 * h;
  const double finial = 0.24 * h;
  const double cornice = 0.028 * h;
  const double bodies = h - moulding - finial - o.num_tiers * cornice;
  double weight_sum = 0;
  for (int k = 0; k < o.num_tiers; ++k) weight_sum += std::pow(0.8, k);
  prisms_.push_back({0.5 * w + 0.03 * w, z, z + moulding, Kind::kBand, -1, 0});
  z += moulding;
  for (int k = 0; k < o.num_tiers; ++k) {
    const double half = 0.5 * w * (1 - 0.17 * k);
    const double body = bodies * std::pow(0.8, k) / weight_sum;
    prisms_.push_back({half, z, z + body, Kind::kWall, k, 0});
    z += body;
    prisms_.push_back(
        {half + 0.025 * w, z, z + cornice, Kind::kBand, -1, k + 1});
    z += cornice;
  }
  // Lotus bud: shrinking tiers, the last one pointed by the apex fan.
  const double top_half = 0.5 * w * (1 - 0.17 * o.num_tiers);
  const int num_finial = 6;
  const double finial_body = 0.55 * finial;
  for (int k = 0; k < num_finial; ++k) {
    const double f = static_cast<double>(k) / num_finial;
    const double half = top_half * (0.92 - 0.55 * f * f);
    const double height = finial_body / num_finial;
    prisms_.push_back({half, z, z + height, Kind::kFinial, -1, k});
    z += height;
  }
  // The subdivisions per side follow the lowest tier's wall.
  num_side_ = std::max(8, static_cast<int>(std::lround(w / o.mesh_spacing_m)));
}

void TowerBuilder::AddPrismWalls(const Prism& prism, double* perimeter0) {
  const Eigen::Vector3d normals[4] = {Eigen::Vector3d::UnitX(),
                                      Eigen::Vector3d::UnitY(),
                                      -Eigen::Vector3d::UnitX(),
                                      -Eigen::Vector3d::UnitY()};
  const double height = prism.z1 - prism.z0;
  const int nt = std::max(
      1, static_cast<int>(std::lround(height / options_.mesh_spacing_m)));
  for (int side = 0; side < 4; ++side) {
    const Eigen::Vector3d n = normals[side];
    const Eigen::Vector3d e = Eigen::Vector3d::UnitZ().cross(n);
    Patch patch;
    const Eigen::Vector3d center = prism.half * n;
    patch.c00 = center - prism.half * e + prism.z0 * Eigen::Vector3d::UnitZ();
    patch.c10 = center + prism.half * e + prism.z0 * Eigen::Vector3d::UnitZ();
    patch.c01 = center - prism.half * e + prism.z1 * Eigen::Vector3d::UnitZ();
    patch.c11 = center + prism.half * e + prism.z1 * Eigen::Vector3d::UnitZ();
    patch.ns = num_side_;
    patch.nt = nt;
    patch.kind = prism.kind;
    patch.normal = n;
    patch.len_s = 2 * prism.half;
    patch.len_t = height;
    patch.perimeter0 = *perimeter0 + side * 2 * prism.half;
    patch.z0 = prism.z0;
    patch.band_index = prism.band_index;
    patch.edge_margin = std::min(0.04, 0.2 * height);
    patch.texel = options_.texel_size_m;
    if (prism.kind == Kind::kWall) {
      patch.face.present = true;
      patch.face.half_height = 0.46 * height;
      patch.face.half_width =
          std::min(0.85 * patch.face.half_height, 0.36 * patch.len_s);
      patch.face.center_u = 0.5 * patch.len_s;
      patch.face.center_v = 0.47 * height;
      patch.face.depth = options_.relief_depth_m;
    }
    patches_.push_back(patch);
  }
  *perimeter0 += 8 * prism.half + 1.7;
}

void TowerBuilder::AddRing(const Prism& lower, const Prism& upper) {
  if (std::abs(lower.half - upper.half) < 1e-9) return;
  const Eigen::Vector3d normals[4] = {Eigen::Vector3d::UnitX(),
                                      Eigen::Vector3d::UnitY(),
                                      -Eigen::Vector3d::UnitX(),
                                      -Eigen::Vector3d::UnitY()};
  const double z = lower.z1;
  const bool facing_up = upper.half < lower.half;
  const double outer = std::max(lower.half, upper.half);
  const double inner = std::min(lower.half, upper.half);
  const int nt = std::max(
      1,
      static_cast<int>(std::lround((outer - inner) / options_.mesh_spacing_m)));
  for (int side = 0; side < 4; ++side) {
    const Eigen::Vector3d n = normals[side];
    const Eigen::Vector3d e = Eigen::Vector3d::UnitZ().cross(n);
    const Eigen::Vector3d up = z * Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d outer_left = outer * n - outer * e + up;
    const Eigen::Vector3d outer_right = outer * n + outer * e + up;
    const Eigen::Vector3d inner_left = inner * n - inner * e + up;
    const Eigen::Vector3d inner_right = inner * n + inner * e + up;
    Patch patch;
    if (facing_up) {
      patch.c00 = outer_left;
      patch.c10 = outer_right;
      patch.c01 = inner_left;
      patch.c11 = inner_right;
      patch.normal = Eigen::Vector3d::UnitZ();
    } else {
      patch.c00 = inner_left;
      patch.c10 = inner_right;
      patch.c01 = outer_left;
      patch.c11 = outer_right;
      patch.normal = -Eigen::Vector3d::UnitZ();
    }
    patch.ns = num_side_;
    patch.nt = nt;
    const bool platform_top = facing_up && lower.kind == Kind::kPlatformWall &&
                              upper.kind != Kind::kPlatformWall;
    patch.kind = platform_top ? Kind::kPlatformTop : Kind::kLedge;
    patch.len_s = 2 * outer;
    patch.len_t = outer - inner;
    patch.z0 = z;
    patch.edge_margin = std::min(0.04, 0.25 * patch.len_t);
    patch.texel = options_.texel_size_m;
    patches_.push_back(patch);
  }
}

void TowerBuilder::PlanTargets() {
  // Patches in order: per prism its four walls (E, N, W, S), then rings.
  // Targets on the upper platform step (one per side), on the lowest tier
  // beside the face (one per side) and on the second tier (two).
  struct Placement {
    Kind kind;
    int tier_or_step;  // tier for walls, step (0, 1) for the platform
    int side;
    double s, v_fraction;
  };
  std::vector<Placement> placements = {
      {Kind::kPlatformWall, 1, 0, 0.22, 0.5},
      {Kind::kPlatformWall, 1, 1, 0.71, 0.5},
      {Kind::kPlatformWall, 1, 2, 0.35, 0.5},
      {Kind::kPlatformWall, 1, 3, 0.80, 0.5},
      {Kind::kWall, 0, 0, 0.84, 0.30},
      {Kind::kWall, 0, 1, 0.16, 0.62},
      {Kind::kWall, 0, 2, 0.83, 0.70},
      {Kind::kWall, 0, 3, 0.17, 0.40},
  };
  if (options_.num_tiers >= 2) {
    placements.push_back({Kind::kWall, 1, 1, 0.82, 0.35});
    placements.push_back({Kind::kWall, 1, 3, 0.81, 0.65});
  }
  const double plate_half = 0.08, disc_radius = 0.04;
  int number = 0;
  for (const Placement& placement : placements) {
    int prism_index = -1;
    for (size_t p = 0; p < prisms_.size(); ++p) {
      const Prism& prism = prisms_[p];
      if (prism.kind != placement.kind) continue;
      if (placement.kind == Kind::kWall && prism.tier != placement.tier_or_step)
        continue;
      if (placement.kind == Kind::kPlatformWall &&
          prism.band_index != placement.tier_or_step)
        continue;
      prism_index = static_cast<int>(p);
    }
    if (prism_index < 0) continue;
    // The prism's walls are the patches with its z range and kind.
    const Prism& prism = prisms_[prism_index];
    for (Patch& patch : patches_) {
      if (patch.kind != prism.kind || patch.z0 != prism.z0 ||
          !patch.IsVertical()) {
        continue;
      }
      const Eigen::Vector3d normals[4] = {Eigen::Vector3d::UnitX(),
                                          Eigen::Vector3d::UnitY(),
                                          -Eigen::Vector3d::UnitX(),
                                          -Eigen::Vector3d::UnitY()};
      if ((patch.normal - normals[placement.side]).norm() > 1e-9) continue;
      FlatSite site;
      site.u = placement.s * patch.len_s;
      site.v = placement.v_fraction * patch.len_t;
      site.radius = plate_half * std::sqrt(2.0) + 0.01;
      patch.flat_sites.push_back(site);
      ControlTarget target;
      char name[16];
      std::snprintf(name, sizeof(name), "T%02d", ++number);
      target.name = name;
      target.normal = patch.normal;
      target.center =
          patch.Base(placement.s, placement.v_fraction) + 0.003 * patch.normal;
      target.disc_radius_m = disc_radius;
      target.plate_half_size_m = plate_half;
      targets_.push_back(target);
    }
  }
  // The levelling bar stands on the ground in front of the south side,
  // its targets facing south.
  const double half_platform = 0.5 * options_.platform_width_m;
  bar_base_ = Eigen::Vector3d(
      0.26 * options_.platform_width_m, -(half_platform + 1.1), 0);
  bar_height_ = std::max(2.3, options_.bar_target_distance_m + 0.8);
  const double low = 0.45;
  for (int k = 0; k < 2; ++k) {
    ControlTarget target;
    target.name = k == 0 ? "B1" : "B2";
    target.normal = -Eigen::Vector3d::UnitY();
    target.center =
        bar_base_ + Eigen::Vector3d(0,
                                    -bar_half_ - 0.003,
                                    low + k * options_.bar_target_distance_m);
    target.disc_radius_m = 0.035;
    target.plate_half_size_m = 0.07;
    target.on_bar = true;
    targets_.push_back(target);
  }
  PlanCodedTargets();
}

// Spots for coded targets: on every vertical wall of the tower and the
// platform, a grid 0.6 m apart of plates clear of the patch's faded edges,
// its carved face and the control plates; codes 0, 1, ... go to spots spread
// evenly over that list.
void TowerBuilder::PlanCodedTargets() {
  if (options_.num_coded_targets == 0) return;
  const CodedTargetOptions coded;
  const int cells = CodedTargetCells(coded.dictionary) + 2;
  const double half = 0.5 * options_.coded_target_side_m * (cells + 2) / cells;
  constexpr double kClearance = 0.05, kStep = 0.6;
  // Evenly spaced values from lo to hi, centred where only one fits.
  const auto spaced = [](double lo, double hi) {
    std::vector<double> values;
    if (hi < lo) return values;
    const int n = static_cast<int>((hi - lo) / kStep) + 1;
    const double first = lo + 0.5 * ((hi - lo) - (n - 1) * kStep);
    for (int i = 0; i < n; ++i) values.push_back(first + i * kStep);
    return values;
  };
  struct Spot {
    size_t patch;
    double u, v;
  };
  std::vector<Spot> spots;
  for (size_t p = 0; p < patches_.size(); ++p) {
    const Patch& patch = patches_[p];
    if ((patch.kind != Kind::kWall && patch.kind != Kind::kPlatformWall) ||
        !patch.IsVertical()) {
      continue;
    }
    const double margin = patch.edge_margin + half;
    for (double v : spaced(margin, patch.len_t - margin)) {
      for (double u : spaced(margin, patch.len_s - margin)) {
        const FaceRelief& face = patch.face;
        if (face.present &&
            std::abs(u - face.center_u) < face.half_width + half + kClearance &&
            std::abs(v - face.center_v) <
                face.half_height + half + kClearance) {
          continue;
        }
        bool clear = true;
        for (const FlatSite& site : patch.flat_sites) {
          clear = clear && std::hypot(u - site.u, v - site.v) >=
                               site.radius + half * std::sqrt(2.0) + kClearance;
        }
        if (clear) spots.push_back({p, u, v});
      }
    }
  }
  const int n = options_.num_coded_targets;
  if (n > static_cast<int>(spots.size())) {
    ThrowInputError("num_coded_targets: the tower has room for ",
                    spots.size(),
                    " coded targets of ",
                    options_.coded_target_side_m,
                    " m, not ",
                    n);
  }
  for (int code = 0; code < n; ++code) {
    const Spot& spot = spots[static_cast<size_t>(
        (code + 0.5) * static_cast<double>(spots.size()) / n)];
    Patch& patch = patches_[spot.patch];
    FlatSite site;
    site.u = spot.u;
    site.v = spot.v;
    site.radius = half * std::sqrt(2.0) + 0.01;
    patch.flat_sites.push_back(site);
    ControlTarget target;
    target.name = StrCat(coded.name_prefix, code);
    target.normal = patch.normal;
    target.center = patch.Base(spot.u / patch.len_s, spot.v / patch.len_t) +
                    0.003 * patch.normal;
    target.plate_half_size_m = half;
    target.marker_half_size_m = 0.5 * options_.coded_target_side_m;
    target.code = code;
    targets_.push_back(target);
  }
}

double TowerBuilder::GeometricDisplacement(const Patch& patch,
                                           double s,
                                           double t) const {
  const double u = s * patch.len_s, v = t * patch.len_t;
  double d = 0;
  const uint32_t seed = stone_.seed();
  switch (patch.kind) {
    case Kind::kWall:
    case Kind::kBand:
    case Kind::kFinial:
    case Kind::kPlatformWall: {
      const double a = patch.perimeter0 + u, z = patch.z0 + v;
      const double scale = patch.kind == Kind::kPlatformWall ? 1.3 : 1.0;
      const Block block = stone_.Masonry(a, z, scale);
      // Each block sits a little proud or back and a little tilted, and
      // its edges are rounded by weathering.
      const double proud =
          0.006 * (Hash01(block.course, block.index, 21, seed) - 0.5);
      const double tilt_x =
          0.008 * (Hash01(block.course, block.index, 22, seed) - 0.5);
      const double tilt_y =
          0.008 * (Hash01(block.course, block.index, 23, seed) - 0.5);
      d += proud + tilt_x * (block.local_x - 0.5 * block.length) +
           tilt_y * (block.local_y - 0.5 * block.height);
      d -= 0.006 * (1 - SmoothStep(0.0, 0.03, block.joint_distance));
      d += 0.005 * Fbm(a / 0.35, z / 0.35, 3, seed + 31);
      if (patch.kind == Kind::kWall) {
        d += WallDecoration(patch, u, v);
        if (patch.face.present) {
          const double fa = (u - patch.face.center_u) / patch.face.half_width;
          const double fb = (v - patch.face.center_v) / patch.face.half_height;
          if (std::abs(fa) < 1.3 && std::abs(fb) < 1.3) {
            d += patch.face.depth * FaceShape(fa, fb);
          }
        }
      } else if (patch.kind == Kind::kBand) {
        d += BandOrnament(a, v / patch.len_t, patch.band_index, 1.0);
      } else if (patch.kind == Kind::kFinial) {
        d += BandOrnament(a, v / patch.len_t, 0, 0.5 + 0.1 * patch.len_s);
      } else {
        // Platform mouldings: a torus at the foot, a fillet at the top.
        d += 0.025 * Gaussian(v - 0.06, 0.04) +
             0.015 * Gaussian(patch.len_t - v - 0.05, 0.025);
      }
      break;
    }
    case Kind::kPlatformTop: {
      const Eigen::Vector3d base = patch.Base(s, t);
      const Block slab = stone_.Paving(base.x(), base.y());
      d += 0.004 * (Hash01(slab.course, slab.index, 24, seed) - 0.5) +
           0.004 * (Hash01(slab.course, slab.index, 25, seed) - 0.5) *
               (slab.local_x - 0.5 * slab.length);
      d -= 0.004 * (1 - SmoothStep(0.0, 0.02, slab.joint_distance));
      d += 0.003 * Fbm(base.x() / 0.4, base.y() / 0.4, 3, seed + 37);
      break;
    }
    case Kind::kLedge: {
      const Eigen::Vector3d base = patch.Base(s, t);
      d += 0.003 * Fbm(base.x() / 0.3, base.y() / 0.3, 3, seed + 41);
      break;
    }
    default:
      break;
  }
  // Flat spots under the target plates.
  for (const FlatSite& site : patch.flat_sites) {
    const double r = std::hypot(u - site.u, v - site.v);
    d *= SmoothStep(site.radius, site.radius + 0.05, r);
  }
  // Fade to zero at the edges, so that neighbouring patches meet.
  const double edge_s = std::min(s, 1 - s) * patch.len_s,
               edge_t = std::min(t, 1 - t) * patch.len_t;
  const double margin = patch.edge_margin;
  d *= SmoothStep(0.0, margin, edge_s) * SmoothStep(0.0, margin, edge_t);
  return d;
}

// Detail finer than the mesh: joints, pits, cracks, grain. Texture only.
double TowerBuilder::FineDisplacement(const Patch& patch,
                                      double s,
                                      double t) const {
  const uint32_t seed = stone_.seed();
  double x, y, joint = 1;
  if (patch.IsVertical() && patch.kind != Kind::kGround) {
    x = patch.perimeter0 + s * patch.len_s;
    y = patch.z0 + t * patch.len_t;
    const Block block =
        stone_.Masonry(x, y, patch.kind == Kind::kPlatformWall ? 1.3 : 1.0);
    joint = block.joint_distance;
  } else {
    const Eigen::Vector3d base = patch.Base(s, t);
    x = base.x();
    y = base.y();
    if (patch.kind == Kind::kPlatformTop) {
      joint = stone_.Paving(x, y).joint_distance;
    }
  }
  double d = -0.007 * (1 - SmoothStep(0.002, 0.008, joint));
  d += 0.0015 * Fbm(x / 0.05, y / 0.05, 3, seed + 51);
  const double pits = Fbm(x / 0.012, y / 0.012, 2, seed + 53);
  d -= 0.002 * SmoothStep(0.45, 0.75, pits);
  const double cracks = RidgedFbm(x / 0.4, y / 0.4, 2, seed + 57);
  d -= 0.002 * SmoothStep(0.90, 0.98, cracks);
  return d;
}

Eigen::Vector3d TowerBuilder::Albedo(const Patch& patch,
                                     double s,
                                     double t,
                                     double cavity) const {
  const uint32_t seed = stone_.seed();
  const Eigen::Vector3d base_point = patch.Base(s, t);
  double x, y;
  Block block;
  bool vertical = patch.IsVertical();
  if (vertical) {
    x = patch.perimeter0 + s * patch.len_s;
    y = patch.z0 + t * patch.len_t;
    block = stone_.Masonry(x, y, patch.kind == Kind::kPlatformWall ? 1.3 : 1.0);
  } else {
    x = base_point.x();
    y = base_point.y();
    block = patch.kind == Kind::kPlatformTop ? stone_.Paving(x, y)
                                             : stone_.Masonry(x, y + 7, 1.0);
  }
  // Grey sandstone, each block its own shade and tint (RGB, linear).
  const double shade =
      0.80 + 0.40 * Hash01(block.course, block.index, 61, seed);
  const double tint = Hash01(block.course, block.index, 62, seed);
  Eigen::Vector3d color = Eigen::Vector3d(0.27, 0.255, 0.225) * shade;
  color += (tint - 0.5) * Eigen::Vector3d(0.05, 0.01, -0.03);
  // Mottling at the metre scale.
  color *= 1 + 0.22 * Fbm(x / 1.3, y / 1.3, 4, seed + 63);
  // Dark lichen and soot in large patches.
  const double lichen =
      SmoothStep(0.05, 0.45, Fbm(x / 0.8 + 9, y / 0.8, 4, seed + 65));
  color = color.cwiseProduct((1 - lichen) * Eigen::Vector3d::Ones() +
                             lichen * Eigen::Vector3d(0.34, 0.36, 0.33));
  // Pale lichen rosettes and orange crust in small spots.
  const double pale =
      SmoothStep(0.50, 0.70, Fbm(x / 0.07, y / 0.07, 2, seed + 67));
  color =
      (1 - 0.6 * pale) * color + 0.6 * pale * Eigen::Vector3d(0.46, 0.46, 0.42);
  const double orange =
      SmoothStep(0.55, 0.72, Fbm(x / 0.1, y / 0.1, 2, seed + 69)) *
      SmoothStep(0.1, 0.4, Fbm(x / 2.0, y / 2.0, 1, seed + 71));
  color = (1 - 0.7 * orange) * color +
          0.7 * orange * Eigen::Vector3d(0.42, 0.22, 0.07);
  if (vertical) {
    // Rain streaks running down the walls, and green damp near the ground.
    const double streak = Fbm(x / 0.05, y / 1.4, 2, seed + 73);
    color *= 1 - 0.28 * SmoothStep(0.05, 0.6, streak);
    const double damp = SmoothStep(1.4, 0.3, y);
    color = color.cwiseProduct(Eigen::Vector3d::Ones() +
                               damp * Eigen::Vector3d(-0.12, 0.02, -0.16));
  }
  // Grain at the millimetre scale.
  color *= 1 + 0.12 * Fbm(x / 0.004, y / 0.004, 2, seed + 75);
  // Dark joints, and crevices darkened by the shade they get from the sky.
  color *= 0.35 + 0.65 * SmoothStep(0.002, 0.007, block.joint_distance);
  color *= std::clamp(1 + 14 * cavity, 0.3, 1.25);
  return color.cwiseMax(0.01).cwiseMin(0.95);
}

void TowerBuilder::PackCharts(int* atlas_width, int* atlas_height) {
  // Shelf packing, tallest charts first.
  struct Item {
    int w, h;
    int* x;
    int* y;
  };
  std::vector<Item> items;
  for (Patch& patch : patches_) {
    patch.chart_w =
        static_cast<int>(std::ceil(patch.len_s / patch.texel)) + 2 * patch.pad;
    patch.chart_h =
        static_cast<int>(std::ceil(patch.len_t / patch.texel)) + 2 * patch.pad;
    items.push_back(
        {patch.chart_w, patch.chart_h, &patch.chart_x, &patch.chart_y});
  }
  for (Chart& chart : target_charts_) {
    items.push_back({chart.w, chart.h, &chart.x, &chart.y});
  }
  items.push_back(
      {ground_chart_.w, ground_chart_.h, &ground_chart_.x, &ground_chart_.y});
  items.push_back({fan_chart_.w, fan_chart_.h, &fan_chart_.x, &fan_chart_.y});
  items.push_back({bar_chart_.w, bar_chart_.h, &bar_chart_.x, &bar_chart_.y});
  int width = 4096;
  for (const Item& item : items) width = std::max(width, item.w);
  std::vector<size_t> order(items.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return items[a].h > items[b].h;
  });
  int x = 0, y = 0, shelf = 0;
  for (size_t i : order) {
    Item& item = items[i];
    if (x + item.w > width) {
      x = 0;
      y += shelf;
      shelf = 0;
    }
    *item.x = x;
    *item.y = y;
    x += item.w;
    shelf = std::max(shelf, item.h);
  }
  *atlas_width = width;
  *atlas_height = y + shelf;
}

void TowerBuilder::DrawChart(const Patch& patch, cv::Mat* atlas) const {
  const int inner_w = patch.chart_w - 2 * patch.pad;
  const int inner_h = patch.chart_h - 2 * patch.pad;
  // The total relief (mesh and finer) on the chart's texels, then the
  // cavity term: how far each texel lies below its smoothed surroundings.
  cv::Mat relief(patch.chart_h, patch.chart_w, CV_32F);
  auto st = [&](int i, int j) {
    return Eigen::Vector2d((i - patch.pad + 0.5) / inner_w,
                           1.0 - (j - patch.pad + 0.5) / inner_h);
  };
  for (int j = 0; j < patch.chart_h; ++j) {
    for (int i = 0; i < patch.chart_w; ++i) {
      const Eigen::Vector2d c = st(i, j);
      const double s = std::clamp(c.x(), 0.0, 1.0),
                   t = std::clamp(c.y(), 0.0, 1.0);
      relief.at<float>(j, i) = static_cast<float>(
          GeometricDisplacement(patch, s, t) + FineDisplacement(patch, s, t));
    }
  }
  cv::Mat smooth;
  const double sigma = 0.015 / patch.texel;
  cv::GaussianBlur(
      relief, smooth, cv::Size(), sigma, sigma, cv::BORDER_REFLECT);
  for (int j = 0; j < patch.chart_h; ++j) {
    cv::Vec3b* row = atlas->ptr<cv::Vec3b>(patch.chart_y + j) + patch.chart_x;
    for (int i = 0; i < patch.chart_w; ++i) {
      const Eigen::Vector2d c = st(i, j);
      const double s = std::clamp(c.x(), 0.0, 1.0),
                   t = std::clamp(c.y(), 0.0, 1.0);
      const double cavity = relief.at<float>(j, i) - smooth.at<float>(j, i);
      const Eigen::Vector3d rgb = Albedo(patch, s, t, cavity);
      row[i] = cv::Vec3b(cv::saturate_cast<uint8_t>(255 * rgb.z()),
                         cv::saturate_cast<uint8_t>(255 * rgb.y()),
                         cv::saturate_cast<uint8_t>(255 * rgb.x()));
    }
  }
}

// Area-weighted vertex normals. Patches, plates and the bar have their own
// vertices, so shading is smooth within a patch and sharp between them.
void ComputeVertexNormals(TriangleMesh* mesh) {
  std::vector<Eigen::Vector3d> sums(mesh->NumVertices(),
                                    Eigen::Vector3d::Zero());
  const auto& p = mesh->vertices.positions;
  for (const Eigen::Vector3i& face : mesh->faces) {
    const Eigen::Vector3d cross =
        (p[face[1]] - p[face[0]]).cross(p[face[2]] - p[face[0]]);
    for (int k = 0; k < 3; ++k) sums[face[k]] += cross;
  }
  mesh->vertices.normals.resize(mesh->NumVertices());
  for (size_t v = 0; v < sums.size(); ++v) {
    const double norm = sums[v].norm();
    mesh->vertices.normals[v] =
        norm > 0 ? Eigen::Vector3f((sums[v] / norm).cast<float>())
                 : Eigen::Vector3f::UnitZ();
  }
}

// Texture coordinate of patch point (s, t) in an atlas of the given size.
Eigen::Vector2f ChartTexcoord(
    const Patch& patch, double s, double t, int atlas_width, int atlas_height) {
  const double x =
      patch.chart_x + patch.pad + s * (patch.chart_w - 2 * patch.pad);
  const double y =
      patch.chart_y + patch.pad + (1 - t) * (patch.chart_h - 2 * patch.pad);
  return Eigen::Vector2f(static_cast<float>(x / atlas_width),
                         static_cast<float>(1 - y / atlas_height));
}

void TowerBuilder::MeshPatch(const Patch& patch, TriangleMesh* mesh) const {
  const int offset = static_cast<int>(mesh->vertices.size());
  const int row = patch.ns + 1;
  for (int j = 0; j <= patch.nt; ++j) {
    for (int i = 0; i <= patch.ns; ++i) {
      const double s = static_cast<double>(i) / patch.ns;
      const double t = static_cast<double>(j) / patch.nt;
      mesh->vertices.positions.push_back(
          patch.Base(s, t) + GeometricDisplacement(patch, s, t) * patch.normal);
    }
  }
  for (int j = 0; j < patch.nt; ++j) {
    for (int i = 0; i < patch.ns; ++i) {
      const int a = offset + j * row + i, b = a + 1, c = a + row, d = c + 1;
      // Alternate the diagonals so that the facets do not line up.
      if ((i + j) % 2 == 0) {
        mesh->faces.emplace_back(a, b, d);
        mesh->faces.emplace_back(a, d, c);
      } else {
        mesh->faces.emplace_back(a, b, c);
        mesh->faces.emplace_back(b, d, c);
      }
    }
  }
}

TowerModel TowerBuilder::Build() {
  TowerModel model;
  PlanPrisms();
  double perimeter0 = 0;
  for (size_t p = 0; p < prisms_.size(); ++p) {
    AddPrismWalls(prisms_[p], &perimeter0);
    if (p + 1 < prisms_.size()) AddRing(prisms_[p], prisms_[p + 1]);
  }
  PlanTargets();

  // Charts that are not patches: target plates (1.25 mm texels), the
  // ground, and a small one for the fans (bottom, apex).
  for (const ControlTarget& target : targets_) {
    const int size =
        static_cast<int>(std::ceil(2 * target.plate_half_size_m / 0.00125));
    target_charts_.push_back({0, 0, size, size});
  }
  const int ground_texels = static_cast<int>(
      std::ceil(options_.ground_size_m / options_.ground_texel_size_m));
  ground_chart_ = {0, 0, ground_texels, ground_texels};
  fan_chart_ = {0, 0, 16, 16};
  bar_chart_ = {0, 0, 8, static_cast<int>(std::ceil(bar_height_ / 0.005))};
  int atlas_width = 0, atlas_height = 0;
  PackCharts(&atlas_width, &atlas_height);
  cv::Mat atlas(atlas_height, atlas_width, CV_8UC3, cv::Scalar(60, 60, 60));

  // Object geometry: each patch's own vertices (so that edges stay sharp
  // in shading), then the fans; charts drawn in parallel.
  TriangleMesh& mesh = model.mesh;
  std::vector<size_t> patch_first_face;
  for (const Patch& patch : patches_) {
    patch_first_face.push_back(mesh.NumFaces());
    MeshPatch(patch, &mesh);
  }
  patch_first_face.push_back(mesh.NumFaces());
  ParallelFor(static_cast<int>(patches_.size()), -1, [&](int p) {
    DrawChart(patches_[p], &atlas);
  });
  // Texture coordinates follow each patch's (s, t) grid.
  mesh.face_texcoords.resize(mesh.NumFaces());
  for (size_t p = 0; p < patches_.size(); ++p) {
    const Patch& patch = patches_[p];
    const int first_vertex = mesh.faces[patch_first_face[p]].minCoeff();
    for (size_t f = patch_first_face[p]; f < patch_first_face[p + 1]; ++f) {
      for (int k = 0; k < 3; ++k) {
        const int local = mesh.faces[f][k] - first_vertex;
        const double s = static_cast<double>(local % (patch.ns + 1)) / patch.ns;
        const double t = static_cast<double>(local / (patch.ns + 1)) / patch.nt;
        mesh.face_texcoords[f][k] =
            ChartTexcoord(patch, s, t, atlas_width, atlas_height);
      }
    }
  }
  AddFans(&mesh);
  // Fan texture coordinates: the middle of the fan chart.
  const Eigen::Vector2f fan_texcoord(
      (fan_chart_.x + 0.5f * fan_chart_.w) / atlas_width,
      1 - (fan_chart_.y + 0.5f * fan_chart_.h) / float(atlas_height));
  for (size_t f = mesh.face_texcoords.size(); f < mesh.NumFaces(); ++f) {
    mesh.face_texcoords.push_back({fan_texcoord, fan_texcoord, fan_texcoord});
  }
  cv::Mat fan_region =
      atlas(cv::Rect(fan_chart_.x, fan_chart_.y, fan_chart_.w, fan_chart_.h));
  fan_region.setTo(cv::Scalar(45, 55, 60));
  // The levelling bar (a closed box, four vertices per side for sharp
  // shading) belongs to the object. A staff painted red and white every
  // 10 cm: a 1D texture along its height.
  for (int j = 0; j < bar_chart_.h; ++j) {
    const double z = (bar_chart_.h - j - 0.5) / bar_chart_.h * bar_height_;
    const bool red = static_cast<int>(std::floor(z / 0.1)) % 2 == 0;
    const double dirt = 0.85 + 0.15 * Hash01(j, 5, options_.seed);
    const cv::Vec3b color =
        red ? cv::Vec3b(
                  uint8_t(12 * dirt), uint8_t(15 * dirt), uint8_t(140 * dirt))
            : cv::Vec3b(uint8_t(195 * dirt),
                        uint8_t(200 * dirt),
                        uint8_t(200 * dirt));
    for (int i = 0; i < bar_chart_.w; ++i) {
      atlas.at<cv::Vec3b>(bar_chart_.y + j, bar_chart_.x + i) = color;
    }
  }
  {
    const double h = bar_half_;
    auto corner = [&](int k) -> Eigen::Vector3d {
      return bar_base_ + Eigen::Vector3d(k & 1 ? h : -h,
                                         k & 2 ? h : -h,
                                         k & 4 ? bar_height_ : 0.0);
    };
    const int quads[6][4] = {{0, 2, 3, 1},
                             {4, 5, 7, 6},
                             {0, 1, 5, 4},
                             {2, 6, 7, 3},
                             {0, 4, 6, 2},
                             {1, 3, 7, 5}};
    for (const auto& quad : quads) {
      const int offset = static_cast<int>(mesh.vertices.size());
      for (int k = 0; k < 4; ++k) {
        mesh.vertices.positions.push_back(corner(quad[k]));
      }
      for (const Eigen::Vector3i& face :
           {Eigen::Vector3i(offset, offset + 1, offset + 2),
            Eigen::Vector3i(offset, offset + 2, offset + 3)}) {
        mesh.faces.push_back(face);
        std::array<Eigen::Vector2f, 3> tc;
        for (int k = 0; k < 3; ++k) {
          const double z = mesh.vertices.positions[face[k]].z();
          tc[k] = Eigen::Vector2f(
              (bar_chart_.x + 0.5f * bar_chart_.w) / atlas_width,
              1 - (bar_chart_.y + float(1 - z / bar_height_) * bar_chart_.h) /
                      float(atlas_height));
        }
        mesh.face_texcoords.push_back(tc);
      }
    }
  }
  model.num_object_faces = mesh.NumFaces();
  AddTargetPlates(&model, &atlas);
  model.num_target_faces = mesh.NumFaces() - model.num_object_faces;
  AddGround(&mesh, &atlas);

  model.texture = atlas;
  model.targets = targets_;
  model.bar_bottom_name = "B1";
  model.bar_top_name = "B2";
  model.object_bounds.setEmpty();
  model.tower_bounds.setEmpty();
  const size_t num_bar_faces = 12;
  for (size_t f = 0; f < model.num_object_faces; ++f) {
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d& p = mesh.vertices.positions[mesh.faces[f][k]];
      model.object_bounds.extend(p);
      if (f + num_bar_faces < model.num_object_faces &&
          p.z() > options_.platform_height_m + 0.05) {
        model.tower_bounds.extend(p);
      }
    }
  }
  ComputeVertexNormals(&mesh);
  return model;
}

void TowerBuilder::AddFans(TriangleMesh* mesh) const {
  // The platform's bottom (facing down) and the finial's apex (a pyramid):
  // fans from one point to the boundary loop of the first and last prism.
  auto loop = [&](const Prism& prism, double z) {
    const Eigen::Vector3d normals[4] = {Eigen::Vector3d::UnitX(),
                                        Eigen::Vector3d::UnitY(),
                                        -Eigen::Vector3d::UnitX(),
                                        -Eigen::Vector3d::UnitY()};
    std::vector<Eigen::Vector3d> points;
    for (int side = 0; side < 4; ++side) {
      const Eigen::Vector3d n = normals[side];
      const Eigen::Vector3d e = Eigen::Vector3d::UnitZ().cross(n);
      for (int i = 0; i < num_side_; ++i) {
        const double s = static_cast<double>(i) / num_side_;
        const Eigen::Vector3d left = prism.half * n - prism.half * e;
        const Eigen::Vector3d right = prism.half * n + prism.half * e;
        points.push_back((1 - s) * left + s * right +
                         z * Eigen::Vector3d::UnitZ());
      }
    }
    return points;  // counter-clockwise seen from above
  };
  {
    const std::vector<Eigen::Vector3d> bottom = loop(prisms_.front(), 0.0);
    const int center = static_cast<int>(mesh->vertices.size());
    mesh->vertices.positions.push_back(Eigen::Vector3d::Zero());
    const int first = center + 1;
    for (const Eigen::Vector3d& p : bottom)
      mesh->vertices.positions.push_back(p);
    const int n = static_cast<int>(bottom.size());
    for (int i = 0; i < n; ++i) {
      mesh->faces.emplace_back(center, first + (i + 1) % n, first + i);
    }
  }
  {
    const Prism& top = prisms_.back();
    const std::vector<Eigen::Vector3d> rim = loop(top, top.z1);
    const int apex = static_cast<int>(mesh->vertices.size());
    // The tip at the tower's full height above the platform.
    mesh->vertices.positions.push_back(
        Eigen::Vector3d(0, 0, options_.platform_height_m + options_.height_m));
    const int first = apex + 1;
    for (const Eigen::Vector3d& p : rim) mesh->vertices.positions.push_back(p);
    const int n = static_cast<int>(rim.size());
    for (int i = 0; i < n; ++i) {
      mesh->faces.emplace_back(apex, first + i, first + (i + 1) % n);
    }
  }
}

void TowerBuilder::AddTargetPlates(TowerModel* model, cv::Mat* atlas) {
  TriangleMesh& mesh = model->mesh;
  const int atlas_width = atlas->cols, atlas_height = atlas->rows;
  for (size_t k = 0; k < targets_.size(); ++k) {
    const ControlTarget& target = targets_[k];
    const Chart& chart = target_charts_[k];
    // Black plate, white disc; anti-aliased by 8 x 8 samples per texel so
    // that the disc's centre of gravity is its centre. A coded target: its
    // marker (white margin, black border, the code's cells; chart row 0 at
    // the top), anti-aliased alike so that its edges lie where they are.
    const double texel = 2 * target.plate_half_size_m / chart.w;
    cv::Mat pattern;
    if (target.code >= 0) {
      pattern =
          CodedTargetPattern(CodedTargetOptions().dictionary, target.code);
    }
    const double cell = 2 * target.plate_half_size_m / (pattern.cols + 2);
    // A coded target's white stays below the photographs' white at the
    // scene's brightest exposure (overcast, about 3): clipped, its edges
    // would be binarised onto the pixel grid, up to half a pixel from where
    // they lie, as an over-exposed print is in a real photograph. The disc
    // targets keep their paper white (a clipped disc keeps its centre).
    const double white_level = target.code >= 0 ? 0.27 : 0.85;
    const double black_level = target.code >= 0 ? 0.02 : 0.03;
    const auto white = [&](double x, double y) {
      if (pattern.empty()) return std::hypot(x, y) < target.disc_radius_m;
      const int c =
          static_cast<int>(std::floor((x + target.plate_half_size_m) / cell)) -
          1;
      const int r =
          static_cast<int>(std::floor((y + target.plate_half_size_m) / cell)) -
          1;
      return c < 0 || r < 0 || c >= pattern.cols || r >= pattern.rows ||
             pattern.at<uint8_t>(r, c) != 0;
    };
    for (int j = 0; j < chart.h; ++j) {
      for (int i = 0; i < chart.w; ++i) {
        int inside = 0;
        for (int b = 0; b < 8; ++b) {
          for (int a = 0; a < 8; ++a) {
            const double x =
                (i + (a + 0.5) / 8) * texel - target.plate_half_size_m;
            const double y =
                (j + (b + 0.5) / 8) * texel - target.plate_half_size_m;
            inside += white(x, y);
          }
        }
        const double value =
            black_level + (white_level - black_level) * inside / 64.0;
        const uint8_t v = cv::saturate_cast<uint8_t>(255 * value);
        atlas->at<cv::Vec3b>(chart.y + j, chart.x + i) = cv::Vec3b(v, v, v);
      }
    }
    // The plate: a square centred on the disc, in the wall's plane.
    const Eigen::Vector3d n = target.normal;
    const Eigen::Vector3d right =
        Eigen::Vector3d::UnitZ().cross(n).normalized();
    const Eigen::Vector3d up = n.cross(right);
    const double h = target.plate_half_size_m;
    const int offset = static_cast<int>(mesh.vertices.size());
    const Eigen::Vector3d corners[4] = {target.center - h * right - h * up,
                                        target.center + h * right - h * up,
                                        target.center + h * right + h * up,
                                        target.center - h * right + h * up};
    const Eigen::Vector2f tcs[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    for (const Eigen::Vector3d& c : corners)
      mesh.vertices.positions.push_back(c);
    auto texcoord = [&](const Eigen::Vector2f& local) {
      return Eigen::Vector2f(
          (chart.x + local.x() * chart.w) / atlas_width,
          1 - (chart.y + (1 - local.y()) * chart.h) / float(atlas_height));
    };
    mesh.faces.emplace_back(offset, offset + 1, offset + 2);
    mesh.face_texcoords.push_back(
        {texcoord(tcs[0]), texcoord(tcs[1]), texcoord(tcs[2])});
    mesh.faces.emplace_back(offset, offset + 2, offset + 3);
    mesh.face_texcoords.push_back(
        {texcoord(tcs[0]), texcoord(tcs[2]), texcoord(tcs[3])});
  }
}

void TowerBuilder::AddGround(TriangleMesh* mesh, cv::Mat* atlas) const {
  const uint32_t seed = stone_.seed() + 1000;
  const double size = options_.ground_size_m;
  const Chart& chart = ground_chart_;
  const double texel = size / chart.w;
  ParallelFor(chart.h, -1, [&](int j) {
    cv::Vec3b* row = atlas->ptr<cv::Vec3b>(chart.y + j) + chart.x;
    for (int i = 0; i < chart.w; ++i) {
      const double x = -0.5 * size + (i + 0.5) * texel;
      const double y = 0.5 * size - (j + 0.5) * texel;
      // Dirt and grass, gravel, and a trodden ring around the platform.
      const double grass =
          SmoothStep(-0.1, 0.35, Fbm(x / 3.0, y / 3.0, 5, seed + 1));
      Eigen::Vector3d color = (1 - grass) * Eigen::Vector3d(0.21, 0.16, 0.11) +
                              grass * Eigen::Vector3d(0.10, 0.14, 0.05);
      color *= 1 + 0.35 * Fbm(x / 0.25, y / 0.25, 4, seed + 2);
      const double gravel =
          SmoothStep(0.55, 0.75, Fbm(x / 0.04, y / 0.04, 2, seed + 3));
      color = (1 - 0.6 * gravel) * color +
              0.6 * gravel * Eigen::Vector3d(0.38, 0.35, 0.31);
      const double r = std::max(std::abs(x), std::abs(y));
      const double path = SmoothStep(0.5 * options_.platform_width_m + 2.5,
                                     0.5 * options_.platform_width_m + 0.5,
                                     r);
      color = (1 - 0.5 * path) * color +
              0.5 * path * Eigen::Vector3d(0.26, 0.22, 0.17);
      color = color.cwiseMax(0.01).cwiseMin(0.9);
      row[i] = cv::Vec3b(cv::saturate_cast<uint8_t>(255 * color.z()),
                         cv::saturate_cast<uint8_t>(255 * color.y()),
                         cv::saturate_cast<uint8_t>(255 * color.x()));
    }
  });
  // A grid of 16 x 16 squares.
  const int n = 16;
  const int offset = static_cast<int>(mesh->vertices.size());
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      mesh->vertices.positions.push_back(Eigen::Vector3d(
          -0.5 * size + size * i / n, -0.5 * size + size * j / n, 0));
    }
  }
  auto texcoord = [&](int i, int j) {
    return Eigen::Vector2f(
        (chart.x + chart.w * float(i) / n) / atlas->cols,
        1 - (chart.y + chart.h * (1 - float(j) / n)) / float(atlas->rows));
  };
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const int a = offset + j * (n + 1) + i, b = a + 1, c = a + n + 1,
                d = c + 1;
      mesh->faces.emplace_back(a, b, d);
      mesh->face_texcoords.push_back(
          {texcoord(i, j), texcoord(i + 1, j), texcoord(i + 1, j + 1)});
      mesh->faces.emplace_back(a, d, c);
      mesh->face_texcoords.push_back(
          {texcoord(i, j), texcoord(i + 1, j + 1), texcoord(i, j + 1)});
    }
  }
}

}  // namespace

std::vector<bool> TowerModel::UnlitFaces() const {
  std::vector<bool> unlit(mesh.NumFaces(), false);
  for (size_t f = num_object_faces; f < num_object_faces + num_target_faces;
       ++f) {
    unlit[f] = true;
  }
  return unlit;
}

TriangleMesh TowerModel::Surface() const {
  // Weld the patches' vertices by position (they meet exactly, up to
  // rounding) so that the surface is one closed manifold per part. Keys are
  // positions rounded to 1 um; a position within 1 % of a rounding boundary
  // also looks in the neighbouring cells, so that two copies that differ in
  // the last bits still meet.
  TriangleMesh surface;
  struct CellHash {
    size_t operator()(const std::array<int, 3>& c) const {
      return (static_cast<size_t>(c[0]) * 73856093u) ^
             (static_cast<size_t>(c[1]) * 19349663u) ^
             (static_cast<size_t>(c[2]) * 83492791u);
    }
  };
  std::unordered_map<std::array<int, 3>, int, CellHash> index_of_cell;
  std::vector<int> new_index(mesh.NumVertices(), -1);
  const double quantum = 1e-6;
  const auto& positions = mesh.vertices.positions;
  auto find = [&](const Eigen::Vector3d& p, const Eigen::Vector3i& cell) {
    const auto it = index_of_cell.find({cell.x(), cell.y(), cell.z()});
    if (it != index_of_cell.end() &&
        (surface.vertices.positions[it->second] - p).norm() < 2 * quantum) {
      return it->second;
    }
    return -1;
  };
  for (size_t f = 0; f < num_object_faces; ++f) {
    Eigen::Vector3i face;
    for (int k = 0; k < 3; ++k) {
      const int v = mesh.faces[f][k];
      if (new_index[v] < 0) {
        const Eigen::Vector3d& p = positions[v];
        const Eigen::Vector3d scaled = p / quantum;
        const Eigen::Vector3i cell(static_cast<int>(std::lround(scaled.x())),
                                   static_cast<int>(std::lround(scaled.y())),
                                   static_cast<int>(std::lround(scaled.z())));
        int found = find(p, cell);
        if (found < 0) {
          // Directions towards a nearby rounding boundary.
          Eigen::Vector3i toward = Eigen::Vector3i::Zero();
          for (int a = 0; a < 3; ++a) {
            const double fraction = scaled(a) - cell(a);
            if (fraction > 0.49) toward(a) = 1;
            if (fraction < -0.49) toward(a) = -1;
          }
          for (int dz = std::min(0, toward.z());
               dz <= std::max(0, toward.z()) && found < 0;
               ++dz) {
            for (int dy = std::min(0, toward.y());
                 dy <= std::max(0, toward.y()) && found < 0;
                 ++dy) {
              for (int dx = std::min(0, toward.x());
                   dx <= std::max(0, toward.x()) && found < 0;
                   ++dx) {
                if (dx || dy || dz)
                  found = find(p, cell + Eigen::Vector3i(dx, dy, dz));
              }
            }
          }
        }
        if (found < 0) {
          found = static_cast<int>(surface.vertices.positions.size());
          surface.vertices.positions.push_back(p);
          index_of_cell.emplace(
              std::array<int, 3>{cell.x(), cell.y(), cell.z()}, found);
        }
        new_index[v] = found;
      }
      face[k] = new_index[v];
    }
    surface.faces.push_back(face);
    surface.face_texcoords.push_back(mesh.face_texcoords[f]);
  }
  ComputeVertexNormals(&surface);
  return surface;
}

TowerModel BuildTower(const TowerOptions& options) {
  options.Check();
  TowerBuilder builder(options);
  return builder.Build();
}

}  // namespace bayon
