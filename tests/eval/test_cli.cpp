// The heslam-eval executable: tables, JSON and plots from real files, and one-line errors with exit 1.
#include <sys/wait.h>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "synthetic_trajectory.hpp"
#include "test_support.hpp"
#include "tools/eval/trajectory_io.hpp"

namespace heslam::eval {
namespace {

struct ToolRun {
  int exit_code = -1;
  std::string out;
  std::string err;
};

std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

ToolRun run_eval(const std::string& arguments, const std::filesystem::path& dir) {
  const auto out = dir / "stdout.txt";
  const auto err = dir / "stderr.txt";
  const std::string command = ((::heslam::test::bin_dir() / "heslam-eval").string() + " " + arguments + " >" +
                               out.string() + " 2>" + err.string());
  const int status = std::system(command.c_str());
  ToolRun run;
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  run.out = slurp(out);
  run.err = slurp(err);
  return run;
}

TEST(EvalCli, ApeOnSyntheticFilesWritesTableJsonAndPlots) {
  const auto dir = test::scratch_dir();
  const Trajectory gt = test::figure_eight();
  Trajectory est = gt;
  for (std::size_t i = 0; i < est.size(); ++i) est.poses_wc[i].translation().z() += (i % 2 == 0 ? 0.1 : -0.1);
  write_trajectory(dir / "gt.csv", gt, Format::euroc);
  write_trajectory(dir / "est.txt", est, Format::heslam_default);
  const ToolRun run = run_eval("ape --gt " + (dir / "gt.csv").string() + " --est " + (dir / "est.txt").string() +
                                   " --align none --json " + (dir / "ape.json").string() + " --plot " +
                                   (dir / "ape.png").string() + " --errors " + (dir / "ape_errors.txt").string(),
                               dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("APE: 400 pairs"), std::string::npos) << run.out;
  // Below 1 m the table is in millimetres with 3 decimals.
  EXPECT_NE(run.out.find("  rmse        100.000 mm         0.000 deg\n"), std::string::npos) << run.out;
  const std::string json = slurp(dir / "ape.json");
  EXPECT_NE(json.find("\"metric\": \"ape\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"association\": \"time\""), std::string::npos) << json;
  const cv::Mat png = cv::imread((dir / "ape.png").string());
  ASSERT_FALSE(png.empty());
  EXPECT_EQ(png.cols, 1400);
  EXPECT_EQ(png.rows, 700);
  // --errors: a header, then one row per pair with the error vector (estimate - ground truth).
  std::istringstream errors(slurp(dir / "ape_errors.txt"));
  std::string header;
  std::getline(errors, header);
  EXPECT_EQ(header, "# est_row stamp_s translation_error_m dx_m dy_m dz_m rotation_error_deg gt_path_m");
  std::size_t rows = 0;
  double gt_path_m = 0.0;  // the ground truth's path length up to the pair's pose
  for (std::string line; std::getline(errors, line); ++rows) {
    std::istringstream fields(line);
    std::size_t est_row = 0;
    double stamp = 0, error = 0, dx = 0, dy = 0, dz = 0, rotation = 0, path = 0;
    ASSERT_TRUE(fields >> est_row >> stamp >> error >> dx >> dy >> dz >> rotation >> path) << line;
    if (rows > 0) gt_path_m += (gt.position_m(rows) - gt.position_m(rows - 1)).norm();
    EXPECT_NEAR(path, gt_path_m, 1e-5);
    EXPECT_EQ(est_row, rows);
    EXPECT_DOUBLE_EQ(stamp, gt.stamps_s[rows]);
    EXPECT_NEAR(error, 0.1, 1e-9);
    EXPECT_NEAR(dz, rows % 2 == 0 ? 0.1 : -0.1, 1e-9);
    EXPECT_NEAR(std::abs(dx) + std::abs(dy) + rotation, 0.0, 1e-9);
  }
  EXPECT_EQ(rows, 400u);

  const ToolRun rpe = run_eval("rpe --gt " + (dir / "gt.csv").string() + " --est " + (dir / "est.txt").string() +
                                   " --delta 10 --unit m --plot " + (dir / "rpe.svg").string() + " --errors " +
                                   (dir / "rpe_errors.txt").string(),
                               dir);
  ASSERT_EQ(rpe.exit_code, 0) << rpe.err;
  const std::string rpe_errors = slurp(dir / "rpe_errors.txt");
  EXPECT_EQ(rpe_errors.rfind("# est_row_i est_row_j stamp_i_s stamp_j_s translation_error_m rotation_error_deg\n", 0),
            0u);
  const std::size_t pairs_end = rpe.out.find(" pairs, ");
  ASSERT_NE(pairs_end, std::string::npos) << rpe.out;
  const std::size_t pairs_begin = rpe.out.rfind(' ', pairs_end - 1) + 1;
  const std::size_t rpe_pairs_printed = std::stoul(rpe.out.substr(pairs_begin, pairs_end - pairs_begin));
  EXPECT_GT(rpe_pairs_printed, 0u);
  EXPECT_EQ(static_cast<std::size_t>(std::count(rpe_errors.begin(), rpe_errors.end(), '\n')), rpe_pairs_printed + 1);
  const std::string svg = slurp(dir / "rpe.svg");
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("RPE translation [m]"), std::string::npos);
  EXPECT_NE(svg.find("x [m]"), std::string::npos);
}

// The machine-readable path: `--json` alone prints only the JSON document on stdout.
double json_translation_rmse_m(const std::string& json) {
  const std::size_t section = json.find("\"translation_m\"");
  if (section == std::string::npos) return -1.0;
  const std::size_t rmse = json.find("\"rmse\": ", section);
  return rmse == std::string::npos ? -1.0 : std::stod(json.substr(rmse + 8));
}

double printed_rmse(const ToolRun& run) { return json_translation_rmse_m(run.out); }

// The camera-rate EuRoC ground truth against itself: zero at the same instants; shifted by 9 ms
// (interpolated), the error a perfect estimator would show if the image stamps were 9 ms off the
// ground truth's clock (docs/tools/eval.md: on this hand-held clip it is 2.77 mm).
TEST(EvalCli, EurocGroundTruthAgainstItselfShiftedWithInterpolation) {
  HESLAM_REQUIRE_SHARED_DATA("euroc_mh01_handheld");
  const auto dir = test::scratch_dir();
  const auto data = ::heslam::test::shared_dataset("euroc_mh01_handheld") / "mav0";
  const std::string gt = (data / "state_groundtruth_estimate0/data.csv").string();
  const std::string extrinsic = (data / "cam0/sensor.yaml").string();
  const std::string table = "ape --gt " + gt + " --extrinsic " + extrinsic + " --est " + gt +
                            " --est-format euroc --est-extrinsic " + extrinsic + " --interpolate-gt";
  const std::string both = table + " --json";
  const ToolRun same = run_eval(both, dir);
  ASSERT_EQ(same.exit_code, 0) << same.err;
  EXPECT_EQ(same.out.rfind("{\n", 0), 0u) << "stdout is the JSON document alone: " << same.out;
  EXPECT_NE(same.out.find("\"pairs\": 160"), std::string::npos) << same.out;
  EXPECT_LT(printed_rmse(same), 1e-9) << same.out;
  const ToolRun shifted = run_eval(both + " --offset 0.009", dir);
  const ToolRun readable = run_eval(table + " --offset 0.009", dir);
  ASSERT_EQ(readable.exit_code, 0) << readable.err;
  char rmse_row[64];
  std::snprintf(rmse_row, sizeof rmse_row, "  rmse    %11.3f mm", printed_rmse(shifted) * 1e3);
  EXPECT_NE(readable.out.find(rmse_row), std::string::npos) << rmse_row << " in\n" << readable.out;
  ASSERT_EQ(shifted.exit_code, 0) << shifted.err;
  std::printf("[ figures  ] MH01 ground truth against itself 9 ms later: ATE rmse %.2f mm\n",
              printed_rmse(shifted) * 1e3);
  EXPECT_GT(printed_rmse(shifted), 0.002);
  EXPECT_LT(printed_rmse(shifted), 0.0035);
}

TEST(EvalCli, PublishedFiguresPrintInFull) {
  HESLAM_REQUIRE_SHARED_DATA("trajectories");
  const auto dir = test::scratch_dir();
  const auto data = ::heslam::test::shared_dataset("trajectories");
  const ToolRun kitti =
      run_eval("kitti --gt " + (data / "kitti_gt_poses/09.txt").string() + " --est " +
                   (data / "kitti_example_results/09.txt").string() + " --align sim3 --full-precision",
               dir);
  ASSERT_EQ(kitti.exit_code, 0) << kitti.err;
  EXPECT_NE(kitti.out.find("translation drift [%]:     2.88411251140"), std::string::npos) << kitti.out;
  EXPECT_NE(kitti.out.find("ATE [m]:                   8.386619228786"), std::string::npos) << kitti.out;
  const ToolRun readable = run_eval("kitti --gt " + (data / "kitti_gt_poses/09.txt").string() + " --est " +
                                        (data / "kitti_example_results/09.txt").string() + " --align sim3",
                                    dir);
  ASSERT_EQ(readable.exit_code, 0) << readable.err;
  EXPECT_NE(readable.out.find("translation drift:  2.884 %"), std::string::npos) << readable.out;
  EXPECT_NE(readable.out.find("ATE:                8.387 m"), std::string::npos) << readable.out;
}

// from_chars reads "nan" and "inf" as numbers; the reader must still refuse them and say where.
TEST(EvalCli, NonFiniteValueNamesFileLineAndColumn) {
  const auto dir = test::scratch_dir();
  test::write_file(dir / "gt.txt", "1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 0 1\n");
  test::write_file(dir / "nan.txt", "# stamp x y z qx qy qz qw\n1.0 0 0 0 0 0 0 1\n2.0 0 NaN 0 0 0 0 1\n");
  const ToolRun nan = run_eval("ape --gt " + (dir / "gt.txt").string() + " --est " + (dir / "nan.txt").string(), dir);
  EXPECT_EQ(nan.exit_code, 1);
  EXPECT_EQ(nan.err, "heslam-eval: " + (dir / "nan.txt").string() + ":3: column 3 is not a finite number ('NaN')\n");
  test::write_file(dir / "inf.csv", "#t,x,y,z,qw,qx,qy,qz\n1000000000,0,0,0,1,0,0,0\n2000000000,inf,0,0,1,0,0,0\n");
  const ToolRun inf = run_eval("ape --gt " + (dir / "inf.csv").string() + " --est " + (dir / "gt.txt").string(), dir);
  EXPECT_EQ(inf.exit_code, 1);
  EXPECT_EQ(inf.err, "heslam-eval: " + (dir / "inf.csv").string() + ":3: column 2 is not a finite number ('inf')\n");
}

// --json FILE keeps the tables on stdout; --json - (or --json alone) prints the JSON document instead.
TEST(EvalCli, JsonToStdoutIsTheDocumentAlone) {
  const auto dir = test::scratch_dir();
  const Trajectory gt = test::figure_eight();
  Trajectory est = gt;
  for (std::size_t i = 0; i < est.size(); ++i) est.poses_wc[i].translation().x() += 0.003;
  write_trajectory(dir / "gt.txt", gt, Format::heslam_default);
  write_trajectory(dir / "est.txt", est, Format::heslam_default);
  const std::string files = "--gt " + (dir / "gt.txt").string() + " --est " + (dir / "est.txt").string();
  for (const std::string json_flag : {"--json -", "--json"}) {
    const ToolRun run = run_eval("rpe " + files + " " + json_flag + " --delta 5 --unit frames --align none", dir);
    ASSERT_EQ(run.exit_code, 0) << run.err;
    EXPECT_EQ(run.out.rfind("{\n  \"metric\": \"rpe\"", 0), 0u) << run.out;
    EXPECT_EQ(run.out.substr(run.out.size() - 2), "}\n") << run.out;
    EXPECT_NEAR(json_translation_rmse_m(run.out), 0.0, 1e-9) << run.out;
  }
  const ToolRun table = run_eval("ape " + files + " --align none --full-precision", dir);
  ASSERT_EQ(table.exit_code, 0) << table.err;
  EXPECT_NE(table.out.find("   translation [m]    rotation [deg]\n  rmse                 0.003                 0\n"),
            std::string::npos)
      << table.out;
}

// The estimate's '# heslam frame:' header against the ground truth's frame (EuRoC csv:
// body, cam0 with --extrinsic). Mixed frames are one line and exit 1 naming the fix; a rectified
// estimate against camera poses is only warned about (positions compare, rotations carry the
// rectifying rotation); a body estimate against body poses is what the recorder writes by default.
TEST(EvalCli, FrameHeaderMustMatchTheGroundTruthsFrame) {
  const auto dir = test::scratch_dir();
  const Trajectory gt = test::figure_eight(50);
  write_trajectory(dir / "gt.csv", gt, Format::euroc);
  test::write_file(dir / "sensor.yaml",
                   "T_BS:\n  cols: 4\n  rows: 4\n  data: [0, -1, 0, 0.1, 1, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]\n");
  Trajectory est = gt;
  est.frame = PoseFrame::body;
  write_trajectory(dir / "body.txt", est);
  est.frame = PoseFrame::rectified;
  write_trajectory(dir / "rectified.txt", est);
  const std::string gt_body = "ape --gt " + (dir / "gt.csv").string();
  const std::string gt_cam0 = gt_body + " --extrinsic " + (dir / "sensor.yaml").string();

  const ToolRun same = run_eval(gt_body + " --est " + (dir / "body.txt").string(), dir);
  EXPECT_EQ(same.exit_code, 0) << same.err;
  EXPECT_EQ(same.err, "");
  EXPECT_NE(same.out.find("  rmse          0.000 mm         0.000 deg\n"), std::string::npos) << same.out;

  const ToolRun body_vs_cam0 = run_eval(gt_cam0 + " --est " + (dir / "body.txt").string(), dir);
  EXPECT_EQ(body_vs_cam0.exit_code, 1);
  EXPECT_EQ(body_vs_cam0.err, "heslam-eval: " + (dir / "body.txt").string() +
                                  " holds poses of the body frame (its '# heslam frame:' header), the ground truth of "
                                  "the cam0 frame (--extrinsic): drop --extrinsic\n");
  EXPECT_EQ(body_vs_cam0.out, "");

  const ToolRun rectified_vs_body = run_eval(gt_body + " --est " + (dir / "rectified.txt").string(), dir);
  EXPECT_EQ(rectified_vs_body.exit_code, 1);
  EXPECT_NE(rectified_vs_body.err.find("add --extrinsic mav0/cam0/sensor.yaml"), std::string::npos)
      << rectified_vs_body.err;

  const ToolRun rectified_vs_cam0 = run_eval(gt_cam0 + " --est " + (dir / "rectified.txt").string(), dir);
  EXPECT_EQ(rectified_vs_cam0.exit_code, 0) << rectified_vs_cam0.err;
  EXPECT_NE(rectified_vs_cam0.err.find("heslam-eval: warning: "), std::string::npos);
  EXPECT_NE(rectified_vs_cam0.err.find("rotation errors include the rectifying rotation"), std::string::npos);
}

TEST(EvalCli, BadInputIsOneLineAndExitOne) {
  const auto dir = test::scratch_dir();
  test::write_file(dir / "gt.txt", "1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 0 1\n");
  test::write_file(dir / "bad.txt", "1.0 0 0 0 0 0 0 1\n\n2.0 0 0 0 nan? 0 0 1\n");
  const ToolRun bad = run_eval("ape --gt " + (dir / "gt.txt").string() + " --est " + (dir / "bad.txt").string(), dir);
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_EQ(bad.err, "heslam-eval: " + (dir / "bad.txt").string() + ":3: expected a number in column 5, got 'nan?'\n");

  const ToolRun unknown = run_eval("ate --gt a --est b", dir);
  EXPECT_EQ(unknown.exit_code, 1);
  EXPECT_EQ(unknown.err, "heslam-eval: unknown command 'ate' (expected ape, rpe or kitti)\n");

  const ToolRun missing = run_eval("rpe --gt " + (dir / "gt.txt").string(), dir);
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_EQ(missing.err, "heslam-eval: missing --est FILE\n");

  const ToolRun align = run_eval("ape --gt x --est y --align sim4", dir);
  EXPECT_EQ(align.exit_code, 1);
  EXPECT_NE(align.err.find("--align: expected none, origin, se3 or sim3, got 'sim4'"), std::string::npos);

  const ToolRun errors = run_eval("kitti --gt x --est y --errors e.txt", dir);
  EXPECT_EQ(errors.exit_code, 1);
  EXPECT_EQ(errors.err, "heslam-eval: --errors: only for ape and rpe (kitti reports per-length segments)\n");

  const ToolRun help = run_eval("--help", dir);
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("usage: heslam-eval"), std::string::npos);
}

TEST(EvalCli, ApeWarnsWhenTheSe3FitOfAStillTrajectoryIsDegenerate) {
  const auto dir = test::scratch_dir();
  write_trajectory(dir / "gt.csv", test::still_wobble(200, 0.002), Format::euroc);
  write_trajectory(dir / "est.txt", test::still_wobble(200, 0.002, 1.0), Format::heslam_default);
  const std::string files = "ape --gt " + (dir / "gt.csv").string() + " --est " + (dir / "est.txt").string();
  const ToolRun se3 = run_eval(files, dir);
  ASSERT_EQ(se3.exit_code, 0) << se3.err;
  EXPECT_NE(se3.err.find("heslam-eval: warning: the alignment's rotation is ill-determined"), std::string::npos)
      << se3.err;
  EXPECT_NE(se3.err.find("--align origin compares from the first pose instead"), std::string::npos) << se3.err;
  const ToolRun origin = run_eval(files + " --align origin", dir);
  ASSERT_EQ(origin.exit_code, 0) << origin.err;
  EXPECT_EQ(origin.err.find("ill-determined"), std::string::npos) << origin.err;
}

}  // namespace
}  // namespace heslam::eval
