// Siconos C++ side of the catchup benchmark: the paper's 3-state diode circuit
// (LCS), driven by the Siconos kernel's own time loop with no Python in it.
//
//     x' = A x + B z + E u(t),   0 <= z  _|_  C x + G u(t) >= 0,   x(0) = 0,  T = 1.
//
// Case 1: G = 0,       u(t) = 16 sin(6 pi t) - 0.5
// Case 2: G = (0,1)^T, u(t) = sign(sin(4 pi t)), sign(0) = 0
//
// It is the C++ twin of `scripts/siconos_circuit.py --scheme siconos` and must
// stay step for step the same model: FirstOrderLinearTIDS(A, b) +
// FirstOrderLinearTIR(C, B) + ComplementarityConditionNSL(2) +
// EulerMoreauOSI(theta) + LCP(lemke|enum) + TimeStepping; per step k -> k+1 the
// DS's b is overwritten in place with (1/h) E int_{t_k}^{t_{k+1}} u and, for
// case 2, the relation's e with G u(t_{k+1}).  The Python driver exists to
// cross-check this one: both run the same kernel, so at equal (case, n, theta,
// solver) their errors agree to rounding; with theta = 0 both reproduce
// catchup's explicit catching-up step (see the Python docstring for why).
//
// Same command line and the same one JSON line on stdout as the Python driver
// (scripts/bench_report.py reads either), plus "driver": "c++".
//
//   siconos_circuit --case {1,2} --n N [--theta TH] [--solver {lemke,enum}]
//                   [--scheme siconos] [--reps R] [--ref PATH] [--out-traj FILE] [--cpu-time]
//
// Build (scripts/bench-vs-siconos does it; Debian packages libsiconos-kernel-dev,
// libsiconos-numerics-dev):
//   g++ -O2 -std=c++17 -isystem /usr/include/siconos -isystem /usr/include/siconos/kernel
//       -isystem /usr/include/siconos/numerics -isystem /usr/include/suitesparse
//       scripts/siconos_circuit.cpp -lsiconos_kernel -lsiconos_numerics
// (the Debian packages ship no pkg-config file, and their CMake config names
// every Siconos component and Boost::boost without finding Boost, so a plain
// compiler line is the robust way in)
#include <SiconosKernel.hpp>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

namespace {

// R1=1, R2=2, R3=1, L2=1, L3=2, C4=1, exactly as in siconos_circuit.py.
const double R1 = 1.0, R2 = 2.0, R3 = 1.0, L2 = 1.0, L3 = 2.0, C4 = 1.0;
const double A_[3][3] = {{0.0, 1.0, 0.0},
                         {-1.0 / (L3 * C4), -(R1 + R3) / L3, R1 / L3},
                         {0.0, R1 / L2, -(R1 + R2) / L2}};
const double B_[3][2] = {{0.0, 0.0}, {1.0 / L3, 1.0 / L3}, {-1.0 / L2, 0.0}};
const double C_[2][3] = {{0.0, 1.0, -1.0}, {0.0, 1.0, 0.0}};
const double E_[3] = {0.0, 1.0 / L3, 1.0 / L2};

[[noreturn]] void die(const std::string &msg) {
  std::fprintf(stderr, "siconos_circuit: %s\n", msg.c_str());
  std::exit(2);
}

// ubar[k] = (1/h) int_{t_k}^{t_{k+1}} u and ue[k] = u(t_{k+1}), k < n: the
// same closed forms as input_tables() in the Python driver, so that both
// drivers feed Siconos the same numbers up to libm's last bit.
void input_tables(int cas, long n, std::vector<double> &ubar, std::vector<double> &ue) {
  const double h = 1.0 / n, pi = M_PI;
  ubar.resize(n);
  ue.resize(n);
  for (long k = 0; k < n; k++) {
    const double t0 = k * h, t1 = (k + 1) * h;   // t_k = k*h, never accumulated
    if (cas == 1) {
      const double a = 6 * pi * t0, b = 6 * pi * t1;
      // 16 (cos a - cos b)/(6 pi) as a product: no cancellation for small h
      const double integ =
          16.0 * 2.0 * std::sin(0.5 * (a + b)) * std::sin(0.5 * (b - a)) / (6 * pi) - 0.5 * h;
      ubar[k] = integ / h;
      ue[k] = 16.0 * std::sin(6 * pi * t1) - 0.5;
    } else {
      // U(t) = int_0^t sign(sin 4 pi s) ds is the triangle wave of period 1/2;
      // it is continuous, so U(t_{k+1}) - U(t_k) is exact across the jumps too.
      auto U = [](double t) {
        const double tau = std::fmod(t, 0.5);
        return tau <= 0.25 ? tau : 0.5 - tau;
      };
      ubar[k] = (U(t1) - U(t0)) / h;
      // sign(sin(4 pi t_{k+1})) in integers: 4 t_{k+1} = 4(k+1)/n, zero where n | 4(k+1)
      const long m = 4 * (k + 1), q = m / n, r = m % n;
      ue[k] = r == 0 ? 0.0 : (q % 2 == 0 ? 1.0 : -1.0);
    }
  }
}

struct Model {
  SP::TimeStepping sim;
  SP::SiconosVector x, b, e;   // the DS's state and b, the relation's e (case 2)
};

Model build(int cas, long n, double theta, int solver_id) {
  auto A = std::make_shared<SimpleMatrix>(3, 3);
  for (unsigned i = 0; i < 3; i++)
    for (unsigned j = 0; j < 3; j++) A->setValue(i, j, A_[i][j]);
  auto C = std::make_shared<SimpleMatrix>(2, 3);
  for (unsigned i = 0; i < 2; i++)
    for (unsigned j = 0; j < 3; j++) C->setValue(i, j, C_[i][j]);
  auto B = std::make_shared<SimpleMatrix>(3, 2);
  for (unsigned i = 0; i < 3; i++)
    for (unsigned j = 0; j < 2; j++) B->setValue(i, j, B_[i][j]);

  auto x0 = std::make_shared<SiconosVector>(3, 0.0);
  auto b0 = std::make_shared<SiconosVector>(3, 0.0);
  auto ds = std::make_shared<FirstOrderLinearTIDS>(x0, A, b0);
  auto rel = std::make_shared<FirstOrderLinearTIR>(C, B);
  if (cas == 2) rel->setePtr(std::make_shared<SiconosVector>(2, 0.0));   // e is null until set
  auto nslaw = std::make_shared<ComplementarityConditionNSL>(2);
  auto inter = std::make_shared<Interaction>(nslaw, rel);
  auto nsds = std::make_shared<NonSmoothDynamicalSystem>(0.0, 1.0);
  nsds->insertDynamicalSystem(ds);
  nsds->link(inter, ds);
  auto osi = std::make_shared<EulerMoreauOSI>(theta);
  auto td = std::make_shared<TimeDiscretisation>(0.0, 1.0 / n);
  auto osnspb = std::make_shared<LCP>(solver_id);
  Model m;
  m.sim = std::make_shared<TimeStepping>(nsds, td, osi, osnspb);
  // The DS keeps pointers: writing through them changes what the next step sees,
  // as the Python driver's numpy views do.
  m.x = ds->x();
  m.b = ds->b();
  m.e = cas == 2 ? rel->e() : SP::SiconosVector();
  return m;
}

// Common times of the grids k/n and j/1000: store every s_sim steps, compare
// with every s_ref-th reference row.
void sample_plan(long n, long &s_sim, long &s_ref) {
  const long g = std::gcd(n, 1000L);
  s_sim = n / g;
  s_ref = 1000 / g;
}

// Only the time loop is timed, as in the Python driver: building the model and
// the input tables are outside it; storing the sampled state is inside, and so
// is the first step's extra cost (about 10 us warm, 0.2 ms in a process's first
// repetition: 0.1 and 2 us a step at n = 100, hence the median over repetitions).
// seconds on the wall clock, or of this process's CPU time (--cpu-time: what
// a loaded machine's other processes do not add)
static double seconds(bool cpu) {
  if (!cpu) return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

double run(int cas, long n, double theta, int solver_id, std::vector<double> &X, bool cpu) {
  Model m = build(cas, n, theta, solver_id);
  std::vector<double> ubar, ue;
  input_tables(cas, n, ubar, ue);
  long s_sim, s_ref;
  sample_plan(n, s_sim, s_ref);
  X.assign(3 * (n / s_sim + 1), 0.0);
  SiconosVector &x = *m.x, &b = *m.b;
  SiconosVector *e = m.e.get();
  for (unsigned i = 0; i < 3; i++) X[i] = x(i);
  long j = 1;
  const double t0 = seconds(cpu);
  for (long k = 0; k < n; k++) {
    for (unsigned i = 0; i < 3; i++) b(i) = E_[i] * ubar[k];
    if (e) (*e)(1) = ue[k];
    m.sim->computeOneStep();
    m.sim->nextStep();
    if ((k + 1) % s_sim == 0) {
      for (unsigned i = 0; i < 3; i++) X[3 * j + i] = x(i);
      j++;
    }
  }
  return seconds(cpu) - t0;
}

// rows t,x1,x2,x3 after one header line (tests/data/README.md)
std::vector<double> load_ref(const std::string &path) {
  std::ifstream f(path);
  if (!f) die("cannot open reference " + path);
  std::string line;
  std::getline(f, line);
  std::vector<double> r;
  while (std::getline(f, line)) {
    if (line.empty()) continue;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) r.push_back(std::strtod(cell.c_str(), nullptr));
  }
  if (r.size() % 4) die("reference " + path + " is not 4 columns");
  return r;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Package version of the kernel library actually linked, as the Python driver
// reports python3-siconos's.
std::string debian_version() {
  std::string out;
  if (FILE *p = popen("dpkg-query -W -f='${Version}' libsiconos-kernel7 2>/dev/null", "r")) {
    char buf[128];
    while (std::fgets(buf, sizeof buf, p)) out += buf;
    pclose(p);
  }
  return out.empty() ? "?" : out;
}

std::string json_str(const std::string &s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    o += c;
  }
  return o + "\"";
}

// repr-like shortest round-trip double, so the JSON matches Python's precision
std::string num(double v) {
  char buf[40];
  for (int p = 1; p <= 17; p++) {
    std::snprintf(buf, sizeof buf, "%.*g", p, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  std::string s = buf;
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";
  return s;
}

}  // namespace

int main(int argc, char **argv) {
  // Siconos calls BLAS on 2x2 and 3x3 blocks; Debian's pthread OpenBLAS then
  // wakes its thread pool on every call, and on this 2-core machine the
  // sched_yield spinning doubles the cost of a step (9-10 us instead of 4.7).
  // OpenBLAS reads the variable when the library loads, before main, so an
  // unset variable is set here and the program restarted; a value the caller
  // chose is kept (and reported).
  if (!std::getenv("OPENBLAS_NUM_THREADS")) {
    setenv("OPENBLAS_NUM_THREADS", "1", 1);
    if (!std::getenv("OMP_NUM_THREADS")) setenv("OMP_NUM_THREADS", "1", 1);
    execv("/proc/self/exe", argv);
    std::fprintf(stderr, "siconos_circuit: could not restart with OPENBLAS_NUM_THREADS=1; "
                         "set it and run again\n");
    return 2;
  }
  const std::string blas_threads = std::getenv("OPENBLAS_NUM_THREADS");
  int cas = 0, reps = 1;
  long n = 0;
  double theta = 0.5;
  std::string solver = "lemke", scheme = "siconos", ref_path, out_traj;
  bool cpu_time = false;
  for (int a = 1; a < argc; a++) {
    const std::string k = argv[a];
    if (k == "--cpu-time") { cpu_time = true; continue; }
    if (k == "-h" || k == "--help") {
      std::printf("usage: siconos_circuit --case {1,2} --n N [--theta TH] [--solver {lemke,enum}]\n"
                  "                       [--scheme siconos] [--reps R] [--ref PATH] [--out-traj FILE]\n"
                  "                       [--cpu-time]   (time the loop by this process's CPU clock)\n");
      return 0;
    }
    if (a + 1 >= argc) die("option " + k + " needs a value");
    const std::string v = argv[++a];
    if (k == "--case") cas = std::atoi(v.c_str());
    else if (k == "--n") n = std::atol(v.c_str());
    else if (k == "--theta") theta = std::strtod(v.c_str(), nullptr);
    else if (k == "--solver") solver = v;
    else if (k == "--scheme") scheme = v;
    else if (k == "--reps") reps = std::atoi(v.c_str());
    else if (k == "--ref") ref_path = v;
    else if (k == "--out-traj") out_traj = v;
    else die("unknown option " + k);
  }
  if (cas != 1 && cas != 2) die("--case must be 1 or 2");
  if (n < 1) die("--n must be a positive integer");
  if (reps < 1) die("--reps must be >= 1");
  if (scheme != "siconos")
    die("--scheme " + scheme + ": only 'siconos' here (catchup-explicit is the Python driver's numpy reference)");
  int solver_id;
  if (solver == "lemke") solver_id = SICONOS_LCP_LEMKE;
  else if (solver == "enum") solver_id = SICONOS_LCP_ENUM;
  else die("--solver must be lemke or enum");
  if (ref_path.empty()) {
    // The binary is built outside the source tree, so it cannot find tests/data
    // from where it lies; the build may name it (-DREF_DIR=...), else run from
    // the repository's root.
#ifdef REF_DIR
    const std::string dir = REF_DIR;
#else
    const std::string dir = "tests/data";
#endif
    ref_path = dir + "/ref_case" + std::to_string(cas) + "_limit_richardson.csv";
  }
  const std::vector<double> ref = load_ref(ref_path);

  std::vector<double> times, X;
  try {
    for (int r = 0; r < reps; r++) times.push_back(run(cas, n, theta, solver_id, X, cpu_time));
  } catch (const std::exception &ex) {
    die(std::string("Siconos: ") + ex.what());
  }

  long s_sim, s_ref;
  sample_plan(n, s_sim, s_ref);
  const long rows = static_cast<long>(X.size() / 3);
  double err = 0.0;
  for (long j = 0; j < rows; j++) {
    const long jr = j * s_ref;
    const double t = static_cast<double>(j * s_sim) / n;
    if (4 * jr + 3 >= static_cast<long>(ref.size()) || std::fabs(ref[4 * jr] - t) > 1e-12)
      die("grid mismatch between the run and " + ref_path);
    for (int i = 0; i < 3; i++) err = std::max(err, std::fabs(X[3 * j + i] - ref[4 * jr + 1 + i]));
  }
  if (!out_traj.empty()) {
    FILE *f = std::fopen(out_traj.c_str(), "w");
    if (!f) die("cannot write " + out_traj);
    std::fprintf(f, "t,x1,x2,x3\n");
    for (long j = 0; j < rows; j++)
      std::fprintf(f, "%.17g,%.17g,%.17g,%.17g\n", static_cast<double>(j * s_sim) / n, X[3 * j],
                   X[3 * j + 1], X[3 * j + 2]);
    std::fclose(f);
  }

  const double med = median(times);
  std::string ts;
  for (size_t i = 0; i < times.size(); i++) ts += (i ? ", " : "") + num(times[i]);
  std::printf("{\"case\": %d, \"n\": %ld, \"scheme\": \"siconos\", \"driver\": \"c++\", "
              "\"theta\": %s, \"solver\": %s, \"reps\": %d, \"median_s\": %s, \"times\": [%s], "
              "\"per_step_us\": %s, \"err_max\": %s, \"n_compared\": %ld, "
              "\"openblas_num_threads\": %s, "
              "\"siconos_version\": {\"debian\": %s, \"module\": \"kernel (C++)\"}}\n",
              cas, n, num(theta).c_str(), json_str(solver).c_str(), reps, num(med).c_str(),
              ts.c_str(), num(med / n * 1e6).c_str(), num(err).c_str(), rows,
              json_str(blas_threads).c_str(), json_str(debian_version()).c_str());
  return 0;
}
