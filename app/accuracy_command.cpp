// `pandora accuracy`: error against run time for the approximations Pandora makes or could make
// (issue 3, point 6). The studies are suggest/accuracy.h, their tables, CSV files and plots
// render/report/accuracy_tables.h; this runs them in turn, prints each table as it is done and
// writes every file in one output transaction.
#include <tbb/global_control.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "analysis/ray_caster.h"
#include "analysis/scene.h"
#include "app/commands.h"
#include "app/session/study.h"
#include "app/output.h"
#include "render/report/accuracy_tables.h"
#include "suggest/accuracy.h"

namespace pandora::app {

int RunAccuracy(const AccuracyArgs& args) {
  using Clock = std::chrono::steady_clock;
  const Clock::time_point start = Clock::now();
  const auto study = session::Study::Load(args.scene);  // the scene and its ray caster, once
  const Scene& scene = study->scene();
  const Rig rig = study->FindRig(args.rig, "--rig");
  const AccuracyOptions options = args.quick ? AccuracyOptions::Quick() : AccuracyOptions();
  options.Check();
  OutputTransaction output;
  AddSceneInputs(output, scene);
  // Staged first, so that a bad --out fails before minutes of work; written last.
  const std::filesystem::path dir(args.out);
  const std::string tables_path = output.Stage((dir / "accuracy_tables.md").string(), "--out");
  const int threads = static_cast<int>(
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  std::printf("accuracy: %s, rig %s (%d cameras), study voxel %g mm, pixel sigma %.3g px, %d threads%s\n",
              scene.path.c_str(), rig.name.c_str(), rig.enabled_count(), 1e3 * scene.study.voxel_size,
              scene.study.pixel_sigma, threads, args.quick ? ", quick" : "");
  std::fflush(stdout);
  const RayCaster* caster = &study->caster();

  std::string markdown = report::AccuracyTablesHeading(scene.path, rig.name);
  std::vector<std::string> written;
  auto emit = [&](const report::AccuracySection& section) {
    std::printf("%s", section.Text().c_str());
    std::fflush(stdout);
    markdown += section.Markdown();
    for (const auto& [name, text] : {std::pair{section.csv_name, section.csv}, std::pair{section.svg_name, section.svg}}) {
      const std::string path = (dir / name).string();
      output.Write(path, "--out", text);
      written.push_back(path);
    }
  };
  emit(report::VoxelSection(RunVoxelStudy(scene, rig, *caster, options)));
  const MonteCarloStudy monte_carlo = RunMonteCarloStudy(scene, rig, *caster, options);
  emit(report::MonteCarloSection(monte_carlo, threads));
  emit(report::SteadySection(RunSteadyStudy(scene, monte_carlo, options)));

  WriteFileAtomically(tables_path, markdown);
  written.push_back(tables_path);
  output.Commit();
  std::printf("\n%.1f s; wrote", std::chrono::duration<double>(Clock::now() - start).count());
  for (const std::string& path : written) std::printf(" %s", std::filesystem::path(path).filename().c_str());
  std::printf(" in %s\n", args.out.c_str());
  return 0;
}

}  // namespace pandora::app
