// SPDX-License-Identifier: BSD-3-Clause
#include "ext/core/errors.h"
#include "ext/core/file_util.h"
#include "ext/features/image_import.h"
#include "tools/command.h"
#include "tools/commands.h"

namespace bayon {

int RunImport(int argc, char** argv) {
  std::string image_path, database_path, log_path;
  ImportOptions options;
  CommandLine command("import",
                      "Create COLMAP camera and image rows for a folder of "
                      "images, with deterministic ids (sorted names) and focal "
                      "length priors from EXIF or the given camera.");
  CLI::App& app = command.app();
  app.add_option("--image_path", image_path, "Folder of images")->required();
  app.add_option("--database_path",
                 database_path,
                 "COLMAP database; created if missing, else images are added")
      ->required();
  command.AddOptions(&options);
  app.add_option("--log_path", log_path, "Append the log to this file");
  if (!command.Parse(argc, argv)) return 0;
  CheckDirectoryExists(image_path, "--image_path");
  options.Check();
  command.StartLog(log_path);

  const ImportSummary summary =
      ImportImages(database_path, image_path, options);
  command.PrintSummary(StrCat(summary.num_added,
                              " images added (",
                              summary.num_skipped,
                              " already present), ",
                              summary.num_cameras,
                              " cameras (",
                              options.camera_model,
                              ", ",
                              summary.num_priors,
                              " with a focal length prior) -> ",
                              database_path));
  return summary.num_added + summary.num_skipped > 0 ? 0 : 1;
}

}  // namespace bayon
