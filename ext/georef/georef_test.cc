// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/georef/control_import.h"
#include "ext/georef/crs.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "tests/testing.h"

namespace bayon {
namespace {

// Metres per degree of latitude, near enough to read a round trip's error.
constexpr double kMetresPerDegree = 111320;

// Near Angkor Thom (UTM zone 48 N), where the Bayon stands: WGS 84 to UTM
// and back within a millimetre; the zone as OpenDroneMap names it.
TEST(Georef, WgsUtmRoundTripWithinAMillimetre) {
  EXPECT_EQ(NormalizeCrs("WGS84 UTM 48N"), "EPSG:32648");
  EXPECT_EQ(NormalizeCrs("WGS84 UTM 19S"), "EPSG:32719");
  EXPECT_EQ(UtmCrsFor(103.8590, 13.4412), "EPSG:32648");
  EXPECT_EQ(UtmCrsFor(-70.6, -33.4), "EPSG:32719");
  EXPECT_FALSE(IsMetricProjectedCrs("EPSG:4326"));
  EXPECT_TRUE(IsMetricProjectedCrs("EPSG:32648"));
  EXPECT_TRUE(IsMetricProjectedCrs(
      NormalizeCrs("+proj=utm +zone=48 +datum=WGS84 +units=m +no_defs")));
  // A grid in US survey feet (New York Long Island) and a compound CRS
  // (UTM with a height system).
  EXPECT_FALSE(IsMetricProjectedCrs("EPSG:2263"));
  EXPECT_TRUE(IsMetricProjectedCrs("EPSG:32632+5783"));
  // Geographic points work in their UTM zone; a grid in feet is refused
  // (PROJ would keep its heights in feet).
  EXPECT_EQ(LocalFrameCrs("EPSG:4326", Eigen::Vector3d(103.86, 13.44, 0)),
            "EPSG:32648");
  EXPECT_EQ(LocalFrameCrs("EPSG:32648", Eigen::Vector3d(372000, 1486000, 0)),
            "EPSG:32648");
  EXPECT_THROW(LocalFrameCrs("EPSG:2263", Eigen::Vector3d(987000, 210000, 0)),
               InputError);
  // A grid with its datum shift attached (a bound CRS) is still that grid.
  EXPECT_TRUE(IsMetricProjectedCrs(NormalizeCrs(
      "+proj=utm +zone=32 +ellps=intl +towgs84=-87,-98,-121 +units=m")));
  const CrsTransform transform("EPSG:4326", "EPSG:32648");
  double worst_m = 0;
  for (int i = 0; i < 25; ++i) {
    const Eigen::Vector3d geographic(
        103.80 + 0.01 * (i % 5), 13.40 + 0.02 * (i / 5), 20 + i);
    const Eigen::Vector3d utm = transform.Forward(geographic);
    // Zone 48's central meridian is 105 E: east of it is west of 500 km.
    EXPECT_GT(utm.x(), 300000);
    EXPECT_LT(utm.x(), 500000);
    EXPECT_NEAR(utm.y(), 1.48e6, 0.02e6);
    EXPECT_DOUBLE_EQ(utm.z(), geographic.z());
    const Eigen::Vector3d back = transform.Inverse(utm);
    const double error_m =
        std::hypot((back.x() - geographic.x()) * kMetresPerDegree *
                       std::cos(geographic.y() * M_PI / 180),
                   (back.y() - geographic.y()) * kMetresPerDegree);
    worst_m = std::max(worst_m, error_m);
  }
  std::cout << "round trip: worst " << worst_m * 1000 << " mm\n";
  EXPECT_LT(worst_m, 0.001);
  // The same point through the zone's PROJ string (as OpenDroneMap's
  // files may give it) lands at the same coordinates.
  const CrsTransform proj_string(
      "EPSG:4326",
      NormalizeCrs("+proj=utm +zone=48 +datum=WGS84 +units=m +no_defs"));
  EXPECT_LT((proj_string.Forward(Eigen::Vector3d(103.859, 13.4412, 0)) -
             transform.Forward(Eigen::Vector3d(103.859, 13.4412, 0)))
                .norm(),
            1e-6);
}

TEST(Georef, UnknownCrsIsNamed) {
  try {
    CrsTransform("EPSG:999999", "EPSG:32648");
    ADD_FAILURE() << "no error";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("EPSG:999999"), std::string::npos)
        << error.what();
  }
  EXPECT_THROW(IsMetricProjectedCrs("not a crs"), InputError);
}

// An OpenDroneMap gcp_list.txt in UTM: the points in the local frame (UTM
// minus an origin to the metre, stated in crs.json), the measurements as
// given, check points by name; unnamed lines grouped by position.
TEST(Georef, ImportsAnOdmGcpListIntoALocalFrame) {
  const std::string dir = testing::TempDir("georef_odm");
  const std::string path = dir + "/gcp_list.txt";
  std::ofstream(path) << "WGS84 UTM 48N\n"
                         "372001.25 1486002.50 21.0 100.5 200.25 a.jpg P1\n"
                         "372001.25 1486002.50 21.0 110.5 210.25 b.jpg P1\n"
                         "372011.25 1486012.50 23.0 300 400 a.jpg P2\n"
                         "# a comment\n"
                         "372021.25 1485992.50 19.0 500 600 b.jpg P3\n";
  ControlImportOptions options;
  options.sigma_m = 0.005;
  options.check_names = "P3";
  const ImportedControl control =
      ImportControl(path, options, {"a.jpg", "b.jpg"});
  EXPECT_EQ(control.frame.source_crs, "WGS84 UTM 48N");
  EXPECT_EQ(control.frame.crs, "EPSG:32648");
  EXPECT_EQ(control.frame.origin, Eigen::Vector3d(372011, 1486003, 21));
  ASSERT_EQ(control.points.size(), 3u);
  EXPECT_TRUE(control.points[0].xyz.isApprox(Eigen::Vector3d(-9.75, -0.5, 0)));
  EXPECT_EQ(control.points[0].sigma, Eigen::Vector3d::Constant(0.005));
  EXPECT_EQ(control.points[0].type, ControlPointType::kControl);
  EXPECT_EQ(control.points[2].type, ControlPointType::kCheck);
  ASSERT_EQ(control.measurements.size(), 4u);
  EXPECT_EQ(control.measurements[1].image_name, "b.jpg");
  // OpenSfM's pixel centres are whole numbers, COLMAP's half ones.
  EXPECT_EQ(control.measurements[1].xy, Eigen::Vector2d(111.0, 210.75));

  WriteImportedControl(dir + "/control", control);
  EXPECT_EQ(ReadControlPoints(dir + "/control/points.txt").size(), 3u);
  EXPECT_EQ(ReadImageMeasurements(dir + "/control/observations.txt").size(),
            4u);
  const GeoFrame frame = ReadGeoFrame(dir + "/control/crs.json");
  EXPECT_EQ(frame.origin, control.frame.origin);
  EXPECT_EQ(frame.crs, "EPSG:32648");
  // Carried beside the products made from a model that has it.
  std::filesystem::create_directories(dir + "/model");
  EXPECT_TRUE(CopyGeoFrame(dir + "/control", dir + "/model"));
  EXPECT_EQ(ReadGeoFrame(dir + "/model/crs.json").origin, frame.origin);
  EXPECT_FALSE(CopyGeoFrame(dir + "/model/none", dir));

  // A photograph that is not the project's, named with the file.
  try {
    ImportControl(path, options, {"a.jpg"});
    ADD_FAILURE() << "no error";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("b.jpg"), std::string::npos);
    EXPECT_NE(std::string(error.what()).find("gcp_list.txt:3:"),
              std::string::npos)
        << error.what();
  }
  // An unknown CRS in the first line, a name at two positions, a check
  // name that is no point: each named.
  std::ofstream(dir + "/bad_crs.txt") << "EPSG:999999\n1 2 3 4 5 a.jpg P1\n";
  try {
    ImportControl(dir + "/bad_crs.txt", options, {});
    ADD_FAILURE() << "no error";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what())
                  .find("bad_crs.txt:1: unknown CRS "
                        "'EPSG:999999'"),
              std::string::npos)
        << error.what();
  }
  std::ofstream(dir + "/twice.txt") << "EPSG:32648\n1 2 3 4 5 a.jpg P1\n"
                                       "1 2 4 4 5 b.jpg P1\n";
  try {
    ImportControl(dir + "/twice.txt", ControlImportOptions(), {});
    ADD_FAILURE() << "no error";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("twice.txt:3"), std::string::npos)
        << error.what();
  }
  options.check_names = "P9";
  EXPECT_THROW(ImportControl(path, options, {}), InputError);
  // A CRS line and no GCP.
  std::ofstream(dir + "/empty.txt") << "EPSG:32648\n";
  EXPECT_THROW(ImportControl(dir + "/empty.txt", ControlImportOptions(), {}),
               InputError);
}

// Geographic coordinates (a CSV in EPSG:4326, longitude first) land in
// their UTM zone; a Metashape reference CSV's accuracy is each point's
// sigma.
TEST(Georef, ImportsGeographicCsvAndMetashapeReference) {
  const std::string dir = testing::TempDir("georef_csv");
  std::ofstream(dir + "/points.csv")
      << "name,x,y,z,sx,sy,sz,type\n"
         "A,103.8590,13.4412,20,0.01,0.01,0.02,control\n"
         "B,103.8592,13.4414,22,0.01,0.01,0.02,check\n";
  ControlImportOptions options;
  options.format = "csv";
  options.crs = "EPSG:4326";
  const ImportedControl control =
      ImportControl(dir + "/points.csv", options, {});
  EXPECT_EQ(control.frame.crs, "EPSG:32648");
  const CrsTransform transform("EPSG:4326", "EPSG:32648");
  EXPECT_LT((control.points[1].xyz + control.frame.origin -
             transform.Forward(Eigen::Vector3d(103.8592, 13.4414, 22)))
                .norm(),
            1e-6);
  EXPECT_EQ(control.points[1].type, ControlPointType::kCheck);
  EXPECT_EQ(control.points[1].sigma, Eigen::Vector3d(0.01, 0.01, 0.02));
  EXPECT_TRUE(control.measurements.empty());

  std::ofstream(dir + "/reference.csv")
      << "#Label,X/East,Y/North,Z/Altitude,Accuracy_(m)\n"
         "\"GCP1\",372001.25,1486002.50,21.0,0.03\n"
         "\"GCP2\",372011.25,1486012.50,23.0,\n";
  options.format = "metashape";
  options.crs = "EPSG:32648";
  options.sigma_m = 0.05;
  const ImportedControl reference =
      ImportControl(dir + "/reference.csv", options, {});
  ASSERT_EQ(reference.points.size(), 2u);
  EXPECT_EQ(reference.points[0].name, "GCP1");
  EXPECT_EQ(reference.points[0].sigma, Eigen::Vector3d::Constant(0.03));
  EXPECT_EQ(reference.points[1].sigma, Eigen::Vector3d::Constant(0.05));
  // Metashape's "point 1" in a file of white-space separated fields.
  std::ofstream(dir + "/labels.csv") << "point 1,372001.25,1486002.50,21.0\n";
  EXPECT_EQ(ImportControl(dir + "/labels.csv", options, {}).points[0].name,
            "point_1");
  // A negative accuracy, and a line whose x is no number after the
  // header: each named with its line.
  std::ofstream(dir + "/negative.csv") << "GCP1,372001.25,1486002.50,21,-0.1\n";
  EXPECT_THROW(ImportControl(dir + "/negative.csv", options, {}), InputError);
  std::ofstream(dir + "/typo.csv") << "Label,X,Y,Z\nGCP1,372001,1486002,21\n"
                                      "GCP2,3720O1,1486002,21\n";
  try {
    ImportControl(dir + "/typo.csv", options, {});
    ADD_FAILURE() << "no error";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("typo.csv:3"), std::string::npos)
        << error.what();
  }
  // csv without a CRS: refused before reading.
  options.crs.clear();
  EXPECT_THROW(ImportControl(dir + "/reference.csv", options, {}), InputError);
}

}  // namespace
}  // namespace bayon
