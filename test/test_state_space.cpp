// f3r_state_space against independent computations: A's eigenvalues (Eigen's nonsymmetric
// solver) against the modal frequencies, A and B against central differences of the nonlinear
// explicit right-hand side, the step response (Eigen's matrix exponential) against the nonlinear
// simulation with an error second order in the input, and C against central differences of the
// loop closure.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <complex>
#include <cstring>
#include <unsupported/Eigen/MatrixFunctions>

#include "flex3rpr/linear.h"
#include "flex3rpr/modal.h"
#include "flex3rpr/linear_export.h"
#include "test_support.h"

#include <fstream>
#include <sstream>
#include <unistd.h>

namespace {

struct StateSpaceDeleter {
  void operator()(f3r_state_space* s) const { f3r_state_space_destroy(s); }
};
using StateSpacePtr = std::unique_ptr<f3r_state_space, StateSpaceDeleter>;

StateSpacePtr MakeStateSpace(const f3r_model* m) {
  f3r_state_space* raw = nullptr;
  f3r_error err{};
  if (f3r_state_space_create(m, &raw, &err) != F3R_OK) throw std::runtime_error(err.message);
  return StateSpacePtr(raw);
}

using Eigen::MatrixXd;
using Eigen::VectorXd;
using MapM = Eigen::Map<const MatrixXd>;

// Fixed-free and fixed-pinned links, undamped, no inputs, off the home pose.
f3r_scene FlexibleScene() {
  f3r_scene s =
      SceneWithLinks(F3R_LINK_FIXED_FREE, 2, F3R_LINK_FIXED_PINNED, 2, F3R_LINK_FIXED_FREE, 3);
  s.platform_pose0[0] = 0.01;
  s.platform_pose0[1] = -0.005;
  s.platform_pose0[2] = 0.05;
  return s;
}

// The outputs y of stage 12 at full coordinates q: rho, theta, pose, tip deflections.
std::vector<double> OutputsOf(const f3r_model* m, const double* q) {
  std::vector<double> y(12);
  for (int i = 0; i < 3; ++i) {
    y[i] = q[F3R_Q_RHO + i];
    y[3 + i] = q[F3R_Q_THETA + i];
    y[6 + i] = q[F3R_Q_X + i];
    y[9 + i] = f3r_model_tip_deflection(m, q, i);
  }
  return y;
}

// y at z = z0 + dz (n values) through the exact loop closure.
std::vector<double> ClosedOutputs(const f3r_model* m, const f3r_state_space* ss, const double* dz) {
  const int n = ss->nx / 2;
  std::vector<double> q(F3R_MAX_Q, 0.0);
  for (int k = 0; k < n; ++k) q[F3R_Q_INDEPENDENT + k] = ss->x0[k] + dz[k];
  if (f3r_model_close_loops(m, q.data()) != F3R_OK) throw std::runtime_error("unreachable");
  return OutputsOf(m, q.data());
}

TEST(StateSpace, LayoutNamesAndOperatingPoint) {
  auto m = MakeModel(FlexibleScene());
  auto ss = MakeStateSpace(m.get());
  const int n = 3 + 2 + 2 + 3;
  ASSERT_EQ(ss->nx, 2 * n);
  EXPECT_EQ(ss->nu, 6);
  EXPECT_EQ(ss->ny, 12);
  EXPECT_STREQ(ss->state_names[0], "x_p");
  EXPECT_STREQ(ss->state_names[2], "phi_p");
  EXPECT_STREQ(ss->state_names[3], "eta_1_1");
  EXPECT_STREQ(ss->state_names[5], "eta_2_1");
  EXPECT_STREQ(ss->state_names[9], "eta_3_3");
  EXPECT_STREQ(ss->state_names[n], "x_p_rate");
  EXPECT_STREQ(ss->state_names[2 * n - 1], "eta_3_3_rate");
  EXPECT_STREQ(ss->input_names[0], "leg_force_1");
  EXPECT_STREQ(ss->input_names[5], "cylinder_torque_3");
  const char* outputs[12] = {
      "rho_1", "rho_2", "rho_3", "theta_1",          "theta_2",          "theta_3",
      "x_p",   "y_p",   "phi_p", "tip_deflection_1", "tip_deflection_2", "tip_deflection_3"};
  for (int k = 0; k < 12; ++k) EXPECT_STREQ(ss->output_names[k], outputs[k]);
  for (int k = 0; k < 2 * n; ++k) EXPECT_EQ(ss->x0[k], k < 3 ? m->scene.platform_pose0[k] : 0.0);
  const std::vector<double> zero(n, 0.0);
  const std::vector<double> y0 = ClosedOutputs(m.get(), ss.get(), zero.data());
  for (int k = 0; k < 12; ++k) EXPECT_EQ(ss->y0[k], y0[k]) << ss->output_names[k];
  for (int k = 0; k < 12 * 6; ++k) EXPECT_EQ(ss->D[k], 0.0);
  // The upper block rows: z' = z'.
  MapM A(ss->A, 2 * n, 2 * n);
  EXPECT_EQ(A.topLeftCorner(n, n).norm(), 0.0);
  EXPECT_EQ((A.topRightCorner(n, n) - MatrixXd::Identity(n, n)).norm(), 0.0);
  EXPECT_EQ(MapM(ss->B, 2 * n, 6).topRows(n).norm(), 0.0);
}

// Undamped, A's eigenvalues are +-i omega_k with omega_k / 2 pi the modal frequencies that
// `flex3rpr_sim --modal` prints (three of them zero: the unactuated platform).
TEST(StateSpace, EigenvaluesOfAAreTheModalFrequencies) {
  for (bool home : {false, true}) {
    f3r_scene s = FlexibleScene();
    if (home) s.platform_pose0[0] = s.platform_pose0[1] = s.platform_pose0[2] = 0.0;
    auto m = MakeModel(s);
    auto ss = MakeStateSpace(m.get());
    const int nx = ss->nx, n = nx / 2;
    double hz[F3R_MAX_Q];
    int count = 0;
    f3r_error err{};
    ASSERT_EQ(f3r_modal_frequencies(m.get(), hz, &count, &err), F3R_OK) << err.message;
    ASSERT_EQ(count, n);
    Eigen::EigenSolver<MatrixXd> solver(MapM(ss->A, nx, nx), false);
    ASSERT_EQ(solver.info(), Eigen::Success);
    std::vector<std::complex<double>> lambda(solver.eigenvalues().data(),
                                             solver.eigenvalues().data() + nx);
    std::sort(lambda.begin(), lambda.end(),
              [](auto a, auto b) { return std::abs(a) < std::abs(b); });
    const double omega_max = 2 * M_PI * hz[n - 1];
    // The six eigenvalues of the three rigid modes (double zeros, defective): the solver finds
    // them at sqrt(rounding x |A|) ~ 1e-3 rad/s.
    for (int k = 0; k < 6; ++k) EXPECT_LT(std::abs(lambda[k]), 1e-2) << k;
    for (int k = 0; k < 3; ++k) EXPECT_LT(hz[k], 1e-3);
    double worst = 0.0;
    for (int k = 3; k < n; ++k) {
      const double omega = 2 * M_PI * hz[k];
      for (int sign = 0; sign < 2; ++sign) {
        const std::complex<double> l = lambda[2 * k + sign];
        EXPECT_LT(std::fabs(l.real()), 1e-9 * omega_max) << "mode " << k;
        // Eigen's nonsymmetric QR on A (|A| ~ omega_max^2, mixed units) loses more digits than
        // the symmetric (Jacobi) solve behind the modal frequencies: ~1e-8 measured.
        EXPECT_NEAR(std::fabs(l.imag()), omega, 5e-8 * omega) << "mode " << k;
        worst = std::max(worst, std::fabs(std::fabs(l.imag()) - omega) / omega);
      }
    }
    std::printf("%s: %d flexible modes %.2f .. %.2f Hz; |Im lambda(A)| / omega - 1 <= %.2e\n",
                home ? "home pose" : "pose (0.01, -0.005, 0.05)", n - 3, hz[3], hz[n - 1], worst);
    RecordProperty(home ? "eigen_rel_error_home" : "eigen_rel_error_off_home",
                   std::to_string(worst));
  }
}

// A's lower rows and B against central differences of the nonlinear minimal ODE
// (f3r_explicit_rhs) at the operating point: d(z'')/dz, d(z'')/dz' and d(z'')/du.
TEST(StateSpace, MatchesTheNonlinearRightHandSideToFirstOrder) {
  f3r_scene s = FlexibleScene();
  s.friction_prismatic[0] = 2.0;  // some damping, so that -M^-1 D is not zero
  s.friction_revolute[2] = 0.01;
  s.links[0].damping_ratio = 0.02;
  auto m = MakeModel(s);
  auto ss = MakeStateSpace(m.get());
  const int nx = ss->nx, n = nx / 2, ny = f3r_state_size(m.get(), F3R_FORMULATION_MINIMAL);
  WorkspacePtr ws(f3r_workspace_create(m.get()));
  auto accel = [&](const std::vector<double>& x, const std::vector<double>& held) {
    std::vector<double> y(ny, 0.0), ydot(ny);
    for (int k = 0; k < nx; ++k) y[k] = ss->x0[k] + x[k];
    if (f3r_explicit_rhs(m.get(), 0.0, y.data(), held.data(), ydot.data(), ws.get()) != F3R_OK)
      throw std::runtime_error("rhs");
    return VectorXd(Eigen::Map<VectorXd>(ydot.data() + n, n));
  };
  MapM A(ss->A, nx, nx), B(ss->B, nx, 6);
  std::vector<double> x(nx, 0.0), held(F3R_MAX_Q, 0.0);
  double worst = 0.0;
  for (int k = 0; k < nx; ++k) {
    const double h = k < 3 ? 1e-6 : k < n ? 1e-8 : 1e-4;  // m (pose), m (eta), per s (rates)
    x[k] = h;
    const VectorXd up = accel(x, held);
    x[k] = -h;
    const VectorXd down = accel(x, held);
    x[k] = 0.0;
    const VectorXd fd = (up - down) / (2 * h);
    const double scale = std::max(fd.norm(), 1.0);
    const double e = (fd - A.col(k).tail(n)).norm() / scale;
    EXPECT_LT(e, 1e-5) << ss->state_names[k];
    worst = std::max(worst, e);
  }
  for (int u = 0; u < 6; ++u) {
    const int force = u < 3 ? F3R_FORCE_RHO + u : F3R_FORCE_THETA + u - 3;
    held[force] = 1.0;
    const VectorXd up = accel(x, held);
    held[force] = -1.0;
    const VectorXd down = accel(x, held);
    held[force] = 0.0;
    const VectorXd fd = (up - down) / 2.0;  // affine in the force: exact up to rounding
    EXPECT_LT((fd - B.col(u).tail(n)).norm(), 1e-9 * fd.norm()) << ss->input_names[u];
  }
  std::printf("A against central differences of the nonlinear rhs: relative error <= %.2e\n",
              worst);
}

// C against the loop closure itself: central differences (h = 1e-6) per column, and a random
// perturbation whose remainder falls four-fold when it is halved (the map's second order).
TEST(StateSpace, OutputRowsAreTheLoopClosuresDerivative) {
  auto m = MakeModel(FlexibleScene());
  auto ss = MakeStateSpace(m.get());
  const int nx = ss->nx, n = nx / 2;
  MapM C(ss->C, 12, nx);
  EXPECT_EQ(C.rightCols(n).norm(), 0.0);
  double worst = 0.0;
  std::vector<double> dz(n, 0.0);
  for (int k = 0; k < n; ++k) {
    const double h = 1e-6;
    dz[k] = h;
    const auto up = ClosedOutputs(m.get(), ss.get(), dz.data());
    dz[k] = -h;
    const auto down = ClosedOutputs(m.get(), ss.get(), dz.data());
    dz[k] = 0.0;
    for (int r = 0; r < 12; ++r) {
      const double fd = (up[r] - down[r]) / (2 * h);
      EXPECT_NEAR(C(r, k), fd, 1e-8 * std::max(1.0, std::fabs(fd)))
          << ss->output_names[r] << " / " << ss->state_names[k];
      worst = std::max(worst, std::fabs(C(r, k) - fd));
    }
  }
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> dir(n);
  for (int k = 0; k < n; ++k) dir[k] = (k < 2 ? 1e-3 : k == 2 ? 1e-2 : 1e-4) * u(rng);
  double remainder[2];
  for (int half = 0; half < 2; ++half) {
    const double scale = half ? 0.5 : 1.0;
    for (int k = 0; k < n; ++k) dz[k] = scale * dir[k];
    const auto y = ClosedOutputs(m.get(), ss.get(), dz.data());
    VectorXd dx = VectorXd::Zero(nx);
    for (int k = 0; k < n; ++k) dx[k] = dz[k];
    const VectorXd lin = C * dx;
    remainder[half] = 0.0;
    for (int r = 0; r < 12; ++r)
      remainder[half] = std::max(remainder[half], std::fabs(y[r] - ss->y0[r] - lin[r]));
  }
  EXPECT_NEAR(remainder[0] / remainder[1], 4.0, 0.1);
  std::printf(
      "C: central differences within %.2e; perturbation remainder %.3e -> %.3e (ratio %.3f)\n",
      worst, remainder[0], remainder[1], remainder[0] / remainder[1]);
}

// The linear step response y0 + C x(t), x(t) = int_0^t exp(A s) ds B u (Eigen's matrix
// exponential of the augmented [A B u; 0 0]), against the nonlinear simulation under the same
// held forces: the difference is the model's second order, so it falls four-fold when the
// input is halved, while the response itself halves.
TEST(StateSpace, StepResponseAgreesWithTheSimulationToFirstOrder) {
  f3r_scene s = FlexibleScene();
  auto m = MakeModel(s);
  auto ss = MakeStateSpace(m.get());
  const int nx = ss->nx;
  MapM A(ss->A, nx, nx), B(ss->B, nx, 6), C(ss->C, 12, nx);
  const double times[4] = {0.002, 0.005, 0.01, 0.02};
  const double u_unit[6] = {2.0, 0.0, 0.0, 0.0, 0.02, 0.0};  // N on rho_1, N m on theta_2
  double error[2], response[2];
  for (int half = 0; half < 2; ++half) {
    const double amp = half ? 0.5 : 1.0;
    VectorXd u(6);
    for (int k = 0; k < 6; ++k) u[k] = amp * u_unit[k];
    f3r_solver_settings set = f3r_solver_settings_from_scene(&s);
    set.rtol = 1e-11;
    set.atol = 1e-13;
    set.max_order = 5;
    f3r_sim* raw = nullptr;
    f3r_error err{};
    ASSERT_EQ(f3r_sim_create(m.get(), &set, &raw, &err), F3R_OK) << err.message;
    SimPtr sim(raw);
    std::vector<double> held(F3R_MAX_Q, 0.0);
    for (int k = 0; k < 3; ++k) {
      held[F3R_FORCE_RHO + k] = u[k];
      held[F3R_FORCE_THETA + k] = u[3 + k];
    }
    ASSERT_EQ(f3r_sim_set_forces(sim.get(), held.data(), &err), F3R_OK) << err.message;
    error[half] = response[half] = 0.0;
    for (double t : times) {
      ASSERT_EQ(f3r_sim_advance(sim.get(), t, &err), F3R_OK) << err.message;
      const f3r_outputs* o = f3r_sim_outputs(sim.get());
      const std::vector<double> y = OutputsOf(m.get(), o->q);
      MatrixXd aug = MatrixXd::Zero(nx + 1, nx + 1);
      aug.topLeftCorner(nx, nx) = A * t;
      aug.topRightCorner(nx, 1) = B * u * t;
      const VectorXd x = aug.exp().topRightCorner(nx, 1);
      const VectorXd dy = C * x;
      for (int r = 6; r < 9; ++r) {  // the platform pose (m, m, rad)
        error[half] = std::max(error[half], std::fabs(y[r] - ss->y0[r] - dy[r]));
        response[half] = std::max(response[half], std::fabs(dy[r]));
      }
      for (int r = 0; r < 3; ++r)  // the strokes follow the pose through C
        EXPECT_NEAR(y[r] - ss->y0[r], dy[r], 0.05 * response[half] + 1e-9) << t;
    }
  }
  const double ratio = error[0] / error[1];
  std::printf(
      "step response, 20 ms: pose response %.3e m -> %.3e m, linear-vs-nonlinear error "
      "%.3e -> %.3e (ratio %.3f)\n",
      response[0], response[1], error[0], error[1], ratio);
  EXPECT_NEAR(response[0] / response[1], 2.0, 1e-9);
  EXPECT_LT(error[0], 0.05 * response[0]);
  EXPECT_GT(ratio, 3.6);
  EXPECT_LT(ratio, 4.4);
  RecordProperty("step_error_ratio", std::to_string(ratio));
}

// --- the export (src/core/accuracy/linear_export.c) ----------------------------------------------

std::vector<unsigned char> ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<unsigned char>(std::istreambuf_iterator<char>(in), {});
}

// Reads the level-4 file back byte by byte: each record's five little-endian int32, its name,
// its doubles (little-endian IEEE, column-major), against the state space's own arrays.
TEST(StateSpaceExport, MatFileIsMatlabLevel4ByteForByte) {
  auto m = MakeModel(FlexibleScene());
  auto ss = MakeStateSpace(m.get());
  const std::string path = "/tmp/f3r_ss_" + std::to_string(getpid()) + ".mat";
  char why[512] = "";
  ASSERT_EQ(f3r_linear_write_mat(ss.get(), path.c_str(), why, sizeof why), 0) << why;
  const std::vector<unsigned char> bytes = ReadBytes(path);
  std::remove(path.c_str());
  size_t at = 0;
  auto int32 = [&]() {
    if (at + 4 > bytes.size()) throw std::runtime_error("short file");
    uint32_t v = 0;
    for (int k = 0; k < 4; ++k) v |= uint32_t(bytes[at + k]) << (8 * k);
    at += 4;
    return int32_t(v);
  };
  auto float64 = [&]() {
    if (at + 8 > bytes.size()) throw std::runtime_error("short file");
    uint64_t v = 0;
    for (int k = 0; k < 8; ++k) v |= uint64_t(bytes[at + k]) << (8 * k);
    at += 8;
    double d;
    std::memcpy(&d, &v, sizeof d);
    return d;
  };
  auto header = [&](const std::string& name, int type, int rows, int cols) {
    EXPECT_EQ(int32(), type) << name;
    EXPECT_EQ(int32(), rows) << name;
    EXPECT_EQ(int32(), cols) << name;
    EXPECT_EQ(int32(), 0) << name << ": imagf";
    ASSERT_EQ(int32(), int(name.size() + 1)) << name;
    EXPECT_EQ(std::string(bytes.begin() + at, bytes.begin() + at + name.size()), name);
    EXPECT_EQ(bytes[at + name.size()], 0) << name << ": NUL";
    at += name.size() + 1;
  };
  const int nx = ss->nx, nu = 6, ny = 12;
  struct Numeric {
    const char* name;
    const double* data;
    int rows, cols;
  } numeric[] = {{"A", ss->A, nx, nx}, {"B", ss->B, nx, nu},  {"C", ss->C, ny, nx},
                 {"D", ss->D, ny, nu}, {"x0", ss->x0, nx, 1}, {"y0", ss->y0, ny, 1}};
  for (const Numeric& v : numeric) {
    header(v.name, 0, v.rows, v.cols);
    for (int k = 0; k < v.rows * v.cols; ++k) {
      const double d = float64();
      ASSERT_EQ(std::memcmp(&d, &v.data[k], sizeof d), 0) << v.name << "[" << k << "]";
    }
  }
  auto names = [&](const std::string& name, const char(*list)[F3R_SS_NAME], int count) {
    size_t width = 0;
    for (int r = 0; r < count; ++r) width = std::max(width, std::strlen(list[r]));
    header(name, 1, count, int(width));
    std::vector<std::string> rows(count);
    for (size_t c = 0; c < width; ++c)
      for (int r = 0; r < count; ++r) rows[r] += char(int(float64()));
    for (int r = 0; r < count; ++r) {
      std::string padded = list[r];
      padded.resize(width, ' ');
      EXPECT_EQ(rows[r], padded) << name;
    }
  };
  names("state_names", ss->state_names, nx);
  names("input_names", ss->input_names, nu);
  names("output_names", ss->output_names, ny);
  EXPECT_EQ(at, bytes.size()) << "nothing after the last record";
}

// The JSON beside it: the same numbers to the bit (17 digits round-trip), matrices as rows.
TEST(StateSpaceExport, JsonHoldsTheSameAsRows) {
  char out[64];
  ASSERT_EQ(f3r_linear_json_path("dir/model.mat", out, sizeof out), 0);
  EXPECT_STREQ(out, "dir/model.json");
  ASSERT_EQ(f3r_linear_json_path("model", out, sizeof out), 0);
  EXPECT_STREQ(out, "model.json");
  EXPECT_EQ(f3r_linear_json_path("a_rather_long_name.mat", out, 8), -1);
  auto m = MakeModel(FlexibleScene());
  auto ss = MakeStateSpace(m.get());
  const std::string path = "/tmp/f3r_ss_" + std::to_string(getpid()) + ".json";
  char why[512] = "";
  ASSERT_EQ(f3r_linear_write_json(ss.get(), path.c_str(), why, sizeof why), 0) << why;
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  std::remove(path.c_str());
  const std::string j = text.str();
  // The numbers of one field, in the order written, and how many rows ("[" after the first).
  auto numbers = [&](const std::string& key, int* rows) {
    const size_t from = j.find("\"" + key + "\": [");
    if (from == std::string::npos) throw std::runtime_error(key + " missing");
    const bool matrix = key.size() == 1;  // A, B, C, D end with "\n  ]"; x0, y0 with "]"
    const size_t to = matrix ? j.find("\n  ]", from) : j.find("]", from);
    const std::string body = j.substr(from + key.size() + 5, to - from - key.size() - 5);
    *rows = int(std::count(body.begin(), body.end(), '['));
    std::vector<double> v;
    for (const char* p = body.c_str(); *p;) {
      if (std::strchr("-0123456789", *p)) {
        char* end;
        v.push_back(std::strtod(p, &end));
        p = end;
      } else {
        ++p;
      }
    }
    return v;
  };
  const int nx = ss->nx;
  struct Field {
    const char* key;
    const double* data;
    int rows, cols;
  } fields[] = {{"A", ss->A, nx, nx}, {"B", ss->B, nx, 6},   {"C", ss->C, 12, nx},
                {"D", ss->D, 12, 6},  {"x0", ss->x0, nx, 1}, {"y0", ss->y0, 12, 1}};
  for (const Field& f : fields) {
    int rows = 0;
    const std::vector<double> v = numbers(f.key, &rows);
    ASSERT_EQ(int(v.size()), f.rows * f.cols) << f.key;
    if (f.cols > 1) {
      EXPECT_EQ(rows, f.rows) << f.key;
    }  // a list of rows
    for (int r = 0; r < f.rows; ++r)
      for (int c = 0; c < f.cols; ++c)
        ASSERT_EQ(v[r * f.cols + c], f.data[c * f.rows + r])
            << f.key << "(" << r << ", " << c << ")";
  }
  EXPECT_NE(j.find("\"state_names\": [\"x_p\", \"y_p\", \"phi_p\", \"eta_1_1\""),
            std::string::npos);
  EXPECT_NE(j.find("\"eta_3_3_rate\"]"), std::string::npos);
  EXPECT_NE(j.find("\"input_names\": [\"leg_force_1\", \"leg_force_2\", \"leg_force_3\", "
                   "\"cylinder_torque_1\", \"cylinder_torque_2\", \"cylinder_torque_3\"]"),
            std::string::npos);
  EXPECT_NE(j.find("\"output_names\": [\"rho_1\""), std::string::npos);
  EXPECT_NE(j.find("\"tip_deflection_3\"]\n}"), std::string::npos);
  EXPECT_NE(j.find("\"nx\": " + std::to_string(nx) + ","), std::string::npos);
}

// The CLI: --linearise writes both files at the pose --set chooses and says so; a file it
// cannot create is an error naming the path, with a non-zero exit.
TEST(StateSpaceExport, CliWritesBothFilesOrNamesThePathItCannotWrite) {
  const std::string stem = "/tmp/f3r_cli_ss_" + std::to_string(getpid());
  const std::string log = stem + ".log";
  const std::string scene = std::string(F3R_SOURCE_DIR) + "/config/scenes/mixed_links.yaml";
  const std::string cmd = std::string(F3R_CLI) + " " + scene + " --linearise " + stem +
                          ".mat --set 'initial.platform_pose=[0.01, -0.005, 0.05]' > " + log +
                          " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  std::ifstream in(log);
  std::stringstream said;
  said << in.rdbuf();
  EXPECT_NE(said.str().find("wrote " + stem + ".mat"), std::string::npos) << said.str();
  EXPECT_NE(said.str().find("nx 16, nu 6, ny 12"), std::string::npos) << said.str();
  const std::vector<unsigned char> mat = ReadBytes(stem + ".mat"), json = ReadBytes(stem + ".json");
  EXPECT_GT(mat.size(), 16u * 16u * 8u);
  EXPECT_NE(std::string(json.begin(), json.end()).find("\"x0\": [0.01, -0.005, 0.05"),
            std::string::npos);
  const std::string bad = "/nonexistent_f3r_dir/model.mat";
  const std::string cmd_bad =
      std::string(F3R_CLI) + " " + scene + " --linearise " + bad + " > " + log + " 2>&1";
  EXPECT_NE(std::system(cmd_bad.c_str()), 0);
  std::ifstream in_bad(log);
  std::stringstream said_bad;
  said_bad << in_bad.rdbuf();
  EXPECT_NE(said_bad.str().find("cannot create " + bad), std::string::npos) << said_bad.str();
  for (const std::string& f : {log, stem + ".mat", stem + ".json"}) std::remove(f.c_str());
}

}  // namespace
