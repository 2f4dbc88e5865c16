// The real opsila binary: bad input fails cleanly (one error line naming the
// flag or file, no output file), good input renders.
#include <gtest/gtest.h>
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>

#include <map>
#include <sstream>

#include <nlohmann/json.hpp>

#include "formats/image/image_io.h"
#include "test_util.h"

namespace opsila {
namespace {

using test::RunResult;
using test::TempDir;
using test::run_opsila;

// A 2x2 square facing +z, one face: a bare .obj (no camera, no lights).
const char* kSquareObj =
    "o square\n"
    "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
    "f 1 2 3 4\n";

struct CliFixture : ::testing::Test {
  TempDir dir;
  std::string scene;
  std::vector<std::string> before;
  void SetUp() override {
    scene = dir.write("tiny.obj", kSquareObj);
    before = dir.entries();
  }
  // Runs `opsila render <args>` and checks the failure contract.
  void expect_rejected(std::vector<std::string> args, const std::string& named, int code = 2) {
    args.insert(args.begin(), "render");
    const RunResult r = run_opsila(args);
    SCOPED_TRACE("stderr: " + r.err);
    if (code < 0)
      EXPECT_NE(r.exit_code, 0);
    else
      EXPECT_EQ(r.exit_code, code);
    const std::vector<std::string> errors = r.error_lines();
    ASSERT_EQ(errors.size(), 1u);
    EXPECT_EQ(errors[0].rfind("opsila: error: ", 0), 0u) << errors[0];
    EXPECT_NE(errors[0].find(named), std::string::npos) << "error does not name '" << named << "'";
    EXPECT_EQ(dir.entries(), before) << "an output file was left behind";
  }
  std::string out(const std::string& name) const { return dir.file(name); }
};

TEST_F(CliFixture, SizeZeroIsRejected) { expect_rejected({scene, "-o", out("x.png"), "--size", "0x0"}, "--size"); }

TEST_F(CliFixture, SizeTooLargeIsRejected) {
  expect_rejected({scene, "-o", out("x.png"), "--size", "100000x100000"}, "--size");
  expect_rejected({scene, "-o", out("x.png"), "--size=16384x16384"}, "2^26");
  expect_rejected({scene, "-o", out("x.png"), "--size", "12x"}, "--size");
}

TEST_F(CliFixture, FovOutOfRangeIsRejected) {
  expect_rejected({scene, "-o", out("x.png"), "--fov", "0"}, "--fov");
  expect_rejected({scene, "-o", out("x.png"), "--fov", "180"}, "--fov");
  expect_rejected({scene, "-o", out("x.png"), "--fov=nan"}, "--fov");
  // In range, but too narrow to frame a model without a camera: the flag is named.
  expect_rejected({scene, "-o", out("x.png"), "--fov", "1e-30"}, "--fov 1e-30: too narrow to frame");
}

TEST_F(CliFixture, DepthAndPesOutOfRangeAreRejected) {
  expect_rejected({scene, "-o", out("x.png"), "--depth", "0"}, "--depth");
  expect_rejected({scene, "-o", out("x.png"), "--depth", "32"}, "--depth");
  expect_rejected({scene, "-o", out("x.png"), "--pes", "0"}, "--pes");
  expect_rejected({scene, "-o", out("x.png"), "--pes", "1025"}, "--pes");
  expect_rejected({scene, "-o", out("x.png"), "--bank-capacity", "-1"}, "--bank-capacity");
  expect_rejected({scene, "-o", out("x.png"), "--routing", "cubes"}, "--routing");
  expect_rejected({scene, "-o", out("x.png"), "--balance", "rays"}, "--balance");
}

// --balance measured from the command line: the pilot frames run, the stats
// say so, and the picture is the one equal banks give.
TEST_F(CliFixture, BalanceMeasuredRendersTheSameImage) {
  const RunResult a = run_opsila({"render", scene, "-o", out("facets.pfm"), "--size", "48x36", "-q"});
  ASSERT_EQ(a.exit_code, 0) << a.err;
  const RunResult b = run_opsila({"render", scene, "-o", out("measured.pfm"), "--size", "48x36", "--balance",
                                  "measured", "--stats", out("measured.json"), "-q"});
  ASSERT_EQ(b.exit_code, 0) << b.err;
  EXPECT_TRUE(test::read_file(out("facets.pfm")) == test::read_file(out("measured.pfm")));
  const nlohmann::json st = nlohmann::json::parse(test::read_file(out("measured.json")));
  EXPECT_EQ(st.at("balance"), "measured");
  EXPECT_GE(st.at("pilot").at("frames").get<int>(), 1);
}

TEST_F(CliFixture, UnknownDeviceIsRejected) {
  // 2 when the platform is there but nothing matches; 3 without any platform.
  const RunResult r = run_opsila({"render", scene, "-o", out("x.png"), "--device", "nosuchdevice"});
  EXPECT_TRUE(r.exit_code == 2 || r.exit_code == 3) << r.exit_code;
  ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
  if (r.exit_code == 2) EXPECT_NE(r.err.find("nosuchdevice"), std::string::npos) << r.err;
  EXPECT_EQ(dir.entries(), before);
  // A blank name would match any device as a substring: refused.
  const RunResult blank = run_opsila({"render", scene, "-o", out("x.png"), "--device", " "});
  EXPECT_EQ(blank.exit_code, 2) << blank.err;
  EXPECT_NE(blank.err.find("--device ' ': blank"), std::string::npos) << blank.err;
  EXPECT_EQ(dir.entries(), before);
  // An index half given is no name: ":" had matched a version string's colon.
  for (const char* spec : {":", "0:", ":0", "0::1"}) {
    const RunResult half = run_opsila({"render", scene, "-o", out("x.png"), "--device", spec});
    EXPECT_EQ(half.exit_code, 2) << spec << ": " << half.err;
    ASSERT_EQ(half.error_lines().size(), 1u) << half.err;
    EXPECT_NE(half.err.find(std::string("--device ") + spec + ": expected an index, PLATFORM:DEVICE"),
              std::string::npos)
        << half.err;
  }
  EXPECT_EQ(dir.entries(), before);
}

// A scene that fails to read gets its error line alone on stderr: the
// device is named only once the scene is read (render and bench alike).
TEST_F(CliFixture, BadSceneContentPrintsOnlyItsError) {
  const std::string bad = dir.write("bad.json", R"({"objects": [{"type": "sphere", "center": [0, 0, 0], "radius": "x"}]})");
  before = dir.entries();
  for (const char* command : {"render", "bench"}) {
    std::vector<std::string> args = {command, bad};
    if (std::string(command) == "render") args.insert(args.end(), {"-o", out("x.png"), "--size", "16x12"});
    const RunResult r = run_opsila(args);
    EXPECT_EQ(r.exit_code, 2) << command;
    std::istringstream lines(r.err);
    std::vector<std::string> all;
    for (std::string line; std::getline(lines, line);) all.push_back(line);
    ASSERT_EQ(all.size(), 1u) << command << ": " << r.err;
    EXPECT_NE(all[0].find("radius"), std::string::npos) << all[0];
    EXPECT_EQ(dir.entries(), before) << command;
  }
}

TEST_F(CliFixture, MalformedVectorsAreRejected) {
  expect_rejected({scene, "-o", out("x.png"), "--light", "1,2"}, "--light");
  expect_rejected({scene, "-o", out("x.png"), "--light", "1,2,3,4"}, "--light");
  expect_rejected({scene, "-o", out("x.png"), "--eye", "1,2,inf"}, "--eye");
  expect_rejected({scene, "-o", out("x.png"), "--ambient", "a,b,c"}, "--ambient");
  // Hexadecimal, which strtod reads (0x10 as 16) and no scene or model file takes.
  expect_rejected({scene, "-o", out("x.png"), "--fov", "0x10"}, "--fov");
  expect_rejected({scene, "-o", out("x.png"), "--eye", "0x1,0,5"}, "--eye");
}

TEST_F(CliFixture, DegenerateCameraIsRejected) {
  expect_rejected({scene, "-o", out("x.png"), "--eye", "0,0,5", "--look-at", "0,0,5"}, "--eye");
  expect_rejected({scene, "-o", out("x.png"), "--reference", "--eye", "0,0,5", "--look-at", "0,0,0", "--up", "0,0,2"},
                  "--up");
  // Only --up given: checked against the framed camera (looking along -(1,1,2)) after loading.
  expect_rejected({scene, "-o", out("x.png"), "--reference", "-q", "--up", "1,1,2"}, "--up");
  // Apart in double, but the float basis underflows: every camera ray
  // would be NaN (the machine hung on them).
  expect_rejected({scene, "-o", out("x.png"), "--eye", "0,0,1e-25", "--look-at", "0,0,0"}, "--eye");
  expect_rejected({scene, "-o", out("x.png"), "--eye", "0,0,5", "--look-at", "0,0,0", "--up", "0,1e-30,0"},
                  "no unit vectors");
  // Squares that are subnormal floats (distances below about 1e-19) gave
  // unit vectors rounded off unit, hence other camera rays, exit 0; those
  // whose squares float holds are taken.
  expect_rejected({scene, "-o", out("x.png"), "--eye", "0,0,3e-23", "--look-at", "0,0,0"}, "--eye");
  expect_rejected({scene, "-o", out("x.png"), "--eye", "0,0,5", "--look-at", "0,0,0", "--up", "0,1e-20,0"}, "--up");
  EXPECT_EQ(run_opsila({"render", scene, "-o", out("near.png"), "--reference", "-q", "--eye", "0,0,2e-19",
                        "--look-at", "0,0,0", "--up", "0,2e-19,0"})
                .exit_code,
            0);
  std::remove(out("near.png").c_str());
  // The scene's camera is sound; only the flag's up vector is too small for float.
  expect_rejected({scene, "-o", out("x.png"), "--reference", "-q", "--up", "1e-38,1e-38,0"}, "opsila: error: --up:");
  // A scene too small to frame (an instance scaled by 1e-25).
  const std::string tiny = dir.write("tiny.json", R"({"objects": [{"type": "instances",
    "model": {"type": "sphere", "center": [0, 0, 0], "radius": 1}, "transforms": [{"scale": 1e-25}]}]})");
  before = dir.entries();
  expect_rejected({tiny, "-o", out("x.png")}, "tiny.json: the camera framing the scene (it has none): the view");
  // An up parallel to the view that --eye or --look-at made so names them,
  // not the scene file (whose camera may have no up, or be framed).
  const std::string ahead = dir.write("ahead.json", R"({"objects": [{"type": "sphere", "center": [0, 0, 0],
    "radius": 1}], "camera": {"eye": [0, 0, 5], "look_at": [0, 0, 0]}})");
  before = dir.entries();
  expect_rejected({ahead, "-o", out("x.png"), "--eye", "0,5,0"},
                  "--eye/--look-at: the camera up (0,1,0) is parallel to the view direction");
  expect_rejected({tiny, "-o", out("x.png"), "--eye", "0,5,0", "--look-at", "0,0,0"},
                  "--eye/--look-at: the camera up (0,1,0) is parallel");
  // A scene file's camera that float cannot hold is named with its line and key.
  const std::string far = dir.write("far.json", "{\"objects\": [{\"type\": \"sphere\", \"center\": [0, 0, 0], "
                                                "\"radius\": 1}],\n\"camera\": {\"eye\": [1e30, 0, 5], \"look_at\": [0, 0, 0],\n"
                                                "  \"up\": [0, 1e-40, 0]}}");
  before = dir.entries();
  expect_rejected({far, "-o", out("x.png")}, "far.json:2: camera: the view from eye 1e+30,0,5");
  expect_rejected({far, "-o", out("x.png"), "--eye", "0,0,5"}, "far.json:3: camera.up: the view from eye 0,0,5");
}

// A listing that could not be written is a failure, said on stderr.
TEST_F(CliFixture, AnUnwritableStandardOutputIsAnError) {
  if (access("/dev/full", W_OK) != 0) GTEST_SKIP() << "no /dev/full to write to";
  for (const std::vector<std::string>& args : {std::vector<std::string>{"devices"}, {"render", "--help"}}) {
    const RunResult r = test::run_program(OPSILA_BINARY, args, {}, "/dev/full");
    EXPECT_EQ(r.exit_code, 2) << args[0];
    ASSERT_EQ(r.error_lines().size(), 1u) << r.err;
    EXPECT_NE(r.error_lines()[0].find("opsila: error: standard output: write failed"), std::string::npos) << r.err;
  }
}

// A name's control bytes (a carriage return, an escape sequence) are
// shown as \xNN: raw, they let a file name rewrite the terminal's line.
TEST_F(CliFixture, ControlBytesInAMessageAreShownNotSent) {
  const RunResult r = test::run_opsila({"render", "a\rFAKE\x1b[2J.json", "-o", out("x.png")});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "opsila: error: a\\x0dFAKE\\x1b[2J.json: cannot open scene (No such file or directory)\n");
  // A line break in a name or a flag's value stays on the one error line.
  const RunResult broken = test::run_opsila({"render", "no\nsuch.json", "-o", out("x.png")});
  EXPECT_EQ(broken.err, "opsila: error: no\\nsuch.json: cannot open scene (No such file or directory)\n");
  const RunResult device = test::run_opsila({"render", scene, "-o", out("x.png"), "--device", "foo\nbar"});
  EXPECT_EQ(device.exit_code, 2);
  EXPECT_EQ(device.error_lines().size(), 1u) << device.err;
  EXPECT_EQ(device.err.find("foo\nbar"), std::string::npos) << device.err;
}

// A standard output whose reader has gone (`opsila render --help | head
// -0`) is a write error like any other, not a death by SIGPIPE.
TEST_F(CliFixture, AClosedPipeIsAWriteErrorNotASignal) {
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  ::close(fds[0]);  // nobody reads
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::signal(SIGPIPE, SIG_DFL);  // as a shell starts it
    ::dup2(fds[1], 1);
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, 2);
    ::execl(OPSILA_BINARY, OPSILA_BINARY, "render", "--help", static_cast<char*>(nullptr));
    ::_exit(127);
  }
  ::close(fds[1]);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_FALSE(WIFSIGNALED(status)) << "killed by signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), 2);
}

TEST_F(CliFixture, UnknownFlagAndMissingValueAreRejected) {
  expect_rejected({scene, "-o", out("x.png"), "--frobnicate"}, "--frobnicate");
  expect_rejected({scene, "-o", out("x.png"), "--size"}, "--size");
  expect_rejected({scene, "-o", out("x.png"), "--depth", "--pes", "2"}, "--depth");
  expect_rejected({scene}, "-o");
  expect_rejected({scene, "-o", out("x.png"), "--depth", "2", "--depth", "3"}, "--depth");
}

TEST_F(CliFixture, MissingOrFolderSceneIsRejected) {
  expect_rejected({dir.file("absent.obj"), "-o", out("x.png"), "--reference"}, "absent.obj");
  expect_rejected({dir.path(), "-o", out("x.png"), "--reference"}, dir.path());
}

TEST_F(CliFixture, BadOutputIsRejected) {
  expect_rejected({scene, "-o", dir.file("missing/x.png"), "--reference"}, "missing/x.png");
  expect_rejected({scene, "-o", out("x.bmp"), "--reference"}, "x.bmp");
  expect_rejected({scene, "-o", out("x.png"), "--item-buffer", dir.file("missing/i.npy"), "--reference"},
                  "missing/i.npy");
  expect_rejected({scene, "-o", out("x.png"), "--stats", out("s.txt"), "--reference"}, "--stats");
}

TEST(Cli, HelpAndVersionExitZero) {
  RunResult r = run_opsila({"--help"});
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("opsila render"), std::string::npos);
  r = run_opsila({"render", "--help"});
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("--item-buffer"), std::string::npos);
  r = run_opsila({"--version"});
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find(OPSILA_VERSION), std::string::npos);
  r = run_opsila({"--version", "x"});  // not ignored: a mistyped command line
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.err, "opsila: error: --version: takes no argument, not 'x'\n");
}

// Each command's help lists each of its flags once (a flag described twice
// had slipped into render's).
TEST(Cli, HelpListsEveryFlagOnce) {
  for (const char* command : {"render", "bench"}) {
    const RunResult r = run_opsila({command, "--help"});
    ASSERT_EQ(r.exit_code, 0) << command;
    std::map<std::string, int> seen;
    std::istringstream lines(r.out);
    for (std::string line; std::getline(lines, line);) {
      const size_t at = line.find_first_not_of(' ');
      if (at == std::string::npos || at == 0 || line[at] != '-') continue;  // not a flag's first line
      std::string flag = line.substr(at, line.find(' ', at) - at);
      if (flag.size() == 2 && line.size() > at + 4 && line.compare(at + 2, 2, ", ") == 0)  // "-o, --output"
        flag = line.substr(at + 4, line.find(' ', at + 4) - at - 4);
      ++seen[flag];
    }
    EXPECT_GT(seen.size(), 3u) << command << ": no flags found in\n" << r.out;
    for (const auto& [flag, count] : seen) EXPECT_EQ(count, 1) << command << " --help lists " << flag << " " << count << " times";
  }
}

TEST(Cli, NoOrUnknownCommandIsAUsageError) {
  RunResult r = run_opsila({});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.error_lines().size(), 1u);
  r = run_opsila({"paint"});
  EXPECT_EQ(r.exit_code, 2);
  ASSERT_EQ(r.error_lines().size(), 1u);
  EXPECT_NE(r.error_lines()[0].find("paint"), std::string::npos);
}

TEST(Cli, DevicesListsOrExplains) {
  const RunResult r = run_opsila({"devices"});
  EXPECT_TRUE(r.exit_code == 0 || r.exit_code == 3) << r.exit_code << " " << r.err;
  if (r.exit_code == 0) {
    EXPECT_NE(r.out.find("0:0"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("(default)"), std::string::npos) << r.out;
  } else {
    EXPECT_EQ(r.error_lines().size(), 1u) << r.err;
  }
}

TEST_F(CliFixture, ReferenceRenderWritesAllOutputs) {
  const RunResult r = run_opsila({"render", scene, "-o", out("x.png"), "--reference", "--size", "32x24",
                                  "--item-buffer", out("items.npy"), "--stats=" + out("stats.json")});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.error_lines().empty()) << r.err;
  EXPECT_NE(r.err.find("opsila: device: "), std::string::npos) << r.err;

  const std::string png = test::read_file(out("x.png"));
  ASSERT_GT(png.size(), 24u);
  EXPECT_EQ(png.substr(1, 3), "PNG");

  const ItemBufferFile items = read_npy_item_buffer(out("items.npy"));
  EXPECT_EQ(items.width, 32);
  EXPECT_EQ(items.height, 24);
  // The camera frames the square: the centre pixel sees it (object 0, facet 0).
  const std::size_t centre = 2 * (12 * 32 + 16);
  EXPECT_EQ(items.items[centre], 0);
  EXPECT_EQ(items.items[centre + 1], 0);

  const nlohmann::json stats = nlohmann::json::parse(test::read_file(out("stats.json")));
  EXPECT_EQ(stats["width"], 32);
  EXPECT_EQ(stats["rays"]["primary"], 32 * 24);
  EXPECT_TRUE(stats["balanced"].get<bool>());
  EXPECT_EQ(stats["version"], OPSILA_VERSION);
}

TEST_F(CliFixture, FlagsOverrideAndEqualsFormWorks) {
  // Looking away from the square: every pixel is the background.
  const RunResult r = run_opsila({"render", scene, "-o=" + out("x.pfm"), "--reference", "-q", "--size=4x3",
                                  "--eye=0,0,5", "--look-at=0,0,10", "--background=0.25,0.5,0.75"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;  // --quiet
  const FloatImage img = read_pfm(out("x.pfm"));
  ASSERT_EQ(img.width, 4);
  ASSERT_EQ(img.height, 3);
  for (std::size_t i = 0; i < img.rgb.size(); i += 3) {
    EXPECT_NEAR(img.rgb[i], 0.25f, 1e-6f);
    EXPECT_NEAR(img.rgb[i + 1], 0.5f, 1e-6f);
    EXPECT_NEAR(img.rgb[i + 2], 0.75f, 1e-6f);
  }
}

TEST_F(CliFixture, DefaultLightSitsAtTheEye) {
  // Eye straight above the square's centre: n.Lv = 1 at the centre pixel, so
  // L = Ia*Ka + Kd = 0.1*0.8 + 0.8 with the default material and ambient.
  const RunResult r = run_opsila({"render", scene, "-o", out("x.pfm"), "--reference", "--size", "5x5",
                                  "--eye", "0,0,3", "--look-at", "0,0,0", "--ambient", "0.1,0.1,0.1"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const FloatImage img = read_pfm(out("x.pfm"));
  const std::size_t centre = 3 * (2 * 5 + 2);
  EXPECT_NEAR(img.rgb[centre], 0.88f, 1e-5f);
}

TEST_F(CliFixture, SkippedFaceWarnsOnceUnlessQuiet) {
  const std::string bad = dir.write("bad.obj", std::string(kSquareObj) + "f 1 2\nf 2 3\n");
  RunResult r = run_opsila({"render", bad, "-o", out("x.png"), "--reference", "--size", "8x8"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("opsila: warning: "), std::string::npos) << r.err;
  r = run_opsila({"render", bad, "-o", out("y.png"), "--reference", "--size", "8x8", "-q"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
}

// A misspelt hook changed nothing without a word: now a warning names it
// and the hook it is nearest to; a hook spelt right, none; -q, none.
TEST_F(CliFixture, AnUnknownOpsilaVariableIsWarnedOfUnlessQuiet) {
  const test::EnvChanges env = {{"OPSILA_QUANT_NODE", "1"}, {"OPSILA_THREADS", "2"}};
  RunResult r = test::run_program(OPSILA_BINARY, {"render", scene, "-o", out("x.png"), "--reference", "--size", "8x8"},
                                  env);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("opsila: warning: OPSILA_QUANT_NODE is set but opsila reads no such variable (did you mean "
                       "OPSILA_QUANT_NODES?)"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(r.err.find("OPSILA_THREADS"), std::string::npos) << r.err;
  r = test::run_program(OPSILA_BINARY, {"render", scene, "-o", out("y.png"), "--reference", "--size", "8x8", "-q"},
                        env);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");
}

// The machine's flags do nothing for the sequential reference: each is
// named (some had been ignored without a word), and -q keeps them quiet.
TEST_F(CliFixture, TheMachinesFlagsAreNamedAsIgnoredByTheReference) {
  const std::vector<std::string> flags = {"--pes", "7", "--bank-capacity", "5", "--work-groups-per-pe", "3",
                                          "--routing", "spheres", "--balance", "work"};
  std::vector<std::string> args = {"render", scene, "-o", out("x.png"), "--reference", "--size", "8x8"};
  args.insert(args.end(), flags.begin(), flags.end());
  RunResult r = run_opsila(args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (std::size_t k = 0; k < flags.size(); k += 2)
    EXPECT_NE(r.err.find("opsila: warning: " + flags[k] + " is ignored with --reference"), std::string::npos)
        << flags[k] << ": " << r.err;
  args[3] = out("y.png");
  args.push_back("-q");
  r = run_opsila(args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");
}

// The OpenCL path on the default device, compared with the reference. Fails
// until the OpenCL renderer is complete.
TEST_F(CliFixture, OpenClRenderMatchesReference) {
  const std::string obj = dir.write("two.obj",
                                    "o a\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3 4\n"
                                    "o b\nv -0.5 -0.5 0.5\nv 0.5 -0.5 0.5\nv 0 0.5 0.5\nf 5 6 7\n");
  const RunResult cl = run_opsila({"render", obj, "-o", out("cl.pfm"), "--size", "40x30", "--pes", "2",
                                   "--item-buffer", out("cl.npy"), "--stats", out("cl.json")});
  ASSERT_EQ(cl.exit_code, 0) << cl.err;
  const nlohmann::json stats = nlohmann::json::parse(test::read_file(out("cl.json")));
  EXPECT_TRUE(stats["balanced"].get<bool>()) << stats["descriptors"].dump();
  EXPECT_EQ(stats["pes"], 2);
  EXPECT_EQ(stats["levels"][0]["pes"].size(), 2u);
  // What a triangle costs on this device (its planned buffers) and this host.
  const nlohmann::json& cost = stats["triangle_cost"];
  EXPECT_GT(cost["triangles"].get<double>(), 0.0);
  EXPECT_GT(cost["device_bytes"].get<std::uint64_t>(), stats["memory"]["bank_bytes_max"].get<std::uint64_t>());
  EXPECT_NEAR(cost["device_bytes_per_triangle"].get<double>(),
              cost["device_bytes"].get<double>() / cost["triangles"].get<double>(), 1e-6);
  EXPECT_GT(cost["host_peak_bytes"].get<std::uint64_t>(), 0u);
  const RunResult ref = run_opsila({"render", obj, "-o", out("ref.pfm"), "--size", "40x30", "--reference",
                                    "--item-buffer", out("ref.npy")});
  ASSERT_EQ(ref.exit_code, 0) << ref.err;
  const FloatImage a = read_pfm(out("cl.pfm")), b = read_pfm(out("ref.pfm"));
  ASSERT_EQ(a.rgb.size(), b.rgb.size());
  EXPECT_LT(test::fraction_off(a.rgb, b.rgb, 2), 0.01);
  EXPECT_GT(test::clamped_psnr(a.rgb, b.rgb), 40.0);
  const ItemBufferFile ia = read_npy_item_buffer(out("cl.npy")), ib = read_npy_item_buffer(out("ref.npy"));
  std::size_t differ = 0;
  for (std::size_t i = 0; i < ia.items.size() && i < ib.items.size(); ++i) differ += ia.items[i] != ib.items[i];
  EXPECT_LE(differ, ia.items.size() / 100);
}

TEST_F(CliFixture, SmoothFlagInterpolatesVertexNormals) {
  // A flat square whose vertex normals lean outwards: flat and smooth shading differ.
  const std::string obj = dir.write("lean.obj",
                                    "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
                                    "vn -0.5 -0.5 1\nvn 0.5 -0.5 1\nvn 0.5 0.5 1\nvn -0.5 0.5 1\n"
                                    "f 1//1 2//2 3//3 4//4\n");
  const std::vector<std::string> view = {"--size", "32x24", "--eye", "0,0,3", "--look-at", "0,0,0", "-q"};
  std::vector<std::string> flat = {"render", obj, "-o", out("flat.pfm")}, smooth = {"render", obj, "-o", out("s.pfm"), "--smooth"};
  flat.insert(flat.end(), view.begin(), view.end());
  smooth.insert(smooth.end(), view.begin(), view.end());
  ASSERT_EQ(run_opsila(flat).exit_code, 0);
  const RunResult r = run_opsila(smooth);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const FloatImage a = read_pfm(out("flat.pfm")), b = read_pfm(out("s.pfm"));
  EXPECT_LT(test::clamped_psnr(a.rgb, b.rgb), 30.0);
  before = dir.entries();
  expect_rejected({obj, "-o", out("x.png"), "--smooth=yes"}, "--smooth");
}

}  // namespace
}  // namespace opsila
