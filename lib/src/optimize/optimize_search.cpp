// The search of an `optimize:` section (fivebar/optimize.hpp): pagmo2's islands, evolved side by
// side and migrating in a ring between rounds; NLopt's COBYLA polish; the checkpoint; the files.
// pagmo2 and NLopt are included here only (docs/architecture.md "Dependencies").
#include <nlopt.hpp>
#include <pagmo/algorithm.hpp>
#include <pagmo/algorithms/cmaes.hpp>
#include <pagmo/algorithms/moead.hpp>
#include <pagmo/algorithms/nsga2.hpp>
#include <pagmo/algorithms/sade.hpp>
#include <pagmo/population.hpp>
#include <pagmo/problem.hpp>
#include <pagmo/utils/hypervolume.hpp>
#include <pagmo/utils/multi_objective.hpp>

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <future>
#include <limits>
#include <map>
#include <mutex>
#include <random>
#include <set>
#include <sstream>
#include <unordered_map>

#include "fivebar/atlas.hpp"
#include "fivebar/csv_reader.hpp"
#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/io.hpp"
#include "fivebar/optimize.hpp"
#include "fivebar/sections/optimize.hpp"
#include "fivebar/sweep.hpp"
#include "csv.hpp"
#include "optimize/optimize_plot.hpp"

namespace fivebar {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr const char* kCheckpointFormat = "fivebar-optimize-checkpoint";
constexpr const char* kShardFormat = "fivebar-optimize-shard";
/// Largest checkpoint or shard file read back (docs/reliability.md "Resource bounds"): they hold
/// the islands' populations and a front, megabytes at most; a larger file (or /dev/zero behind
/// a link) is refused while reading.
constexpr std::uintmax_t kMaxOptimizeFileBytes = std::uintmax_t{256} << 20;

/// A checkpoint or shard file (`what`), parsed: InputError naming it past kMaxOptimizeFileBytes
/// (checked while reading) or when it is not JSON.
Json read_optimize_file(const std::filesystem::path& path, const std::string& what) {
  try {
    return Json::parse(csv::read_bounded(path, kMaxOptimizeFileBytes, what));
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(path.string() + ": not a " + what + " of fivebar optimize (" + e.what() + ")");
  }
}
/// Least time between two checkpoints of a run (docs/reliability.md "Resource bounds").
constexpr double kCheckpointSeconds = 1.0;

/// SplitMix64 of a combination: the seeds of island i's population and of its round r algorithm.
std::uint64_t mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}
unsigned seed32(std::uint64_t seed, std::uint64_t island, std::uint64_t round) {
  return unsigned(mix(mix(mix(seed) ^ island) ^ round) & 0xffffffffu);
}

/// The pagmo user-defined problem: evaluates through OptimizeProblem and logs every candidate in
/// its island's log (each island is evolved by one thread at a time).
/// Thrown by an evaluation once the wall-time budget is spent or the stop flag is set: the round
/// in progress is abandoned (the islands go back to their state before it).
struct Halt {};

struct Deadline {
  std::chrono::steady_clock::time_point end;
  const std::atomic<bool>* stop = nullptr;
  bool passed() const { return (stop && stop->load()) || std::chrono::steady_clock::now() >= end; }
};

/// The evaluation cache of a run (docs/optimize.md "Evaluation cache"), shared by the islands of a
/// process: keyed by the canonical design (OptimizeProblem::snap(): the variables after their step
/// rounding; tied keys are one variable and no number is set by two, so equal keys are equal
/// designs). A design asked for while another thread evaluates it waits for that evaluation, so
/// every distinct design is evaluated exactly once, whatever the thread count.
class EvaluationCache {
 public:
  explicit EvaluationCache(const OptimizeProblem& p) : p_(p) {}
  /// The candidate of `x` (snapped), evaluated only when no thread has evaluated it yet.
  OptimizeCandidate get(const std::vector<double>& x) {
    std::vector<double> key = p_.snap(x);
    std::shared_future<OptimizeCandidate> pending;
    std::promise<OptimizeCandidate> mine;
    {
      std::lock_guard<std::mutex> lock(mu_);
      const auto it = map_.find(key);
      if (it != map_.end()) {
        ++hits_;
        pending = it->second;
      } else {
        map_.emplace(key, mine.get_future().share());
      }
    }
    if (pending.valid()) return pending.get();
    try {
      OptimizeCandidate c = p_.evaluate(key);
      mine.set_value(c);
      return c;
    } catch (...) {
      mine.set_exception(std::current_exception());
      throw;
    }
  }
  /// Known candidates (a resumed run's): later requests of them are hits.
  void insert(const OptimizeCandidate& c) {
    std::promise<OptimizeCandidate> done;
    OptimizeCandidate k = c;
    k.island = -1;
    k.round = 0;
    k.evaluation = 0;
    done.set_value(std::move(k));
    std::lock_guard<std::mutex> lock(mu_);
    map_.emplace(c.x, done.get_future().share());
  }
  std::uint64_t hits() const {
    std::lock_guard<std::mutex> lock(mu_);
    return hits_;
  }

 private:
  struct Hash {
    std::size_t operator()(const std::vector<double>& x) const {
      std::uint64_t h = 0x243f6a8885a308d3ull;
      for (double v : x) {
        std::uint64_t bits = 0;
        std::memcpy(&bits, &v, sizeof bits);
        h = mix(h ^ bits);
      }
      return std::size_t(h);
    }
  };
  const OptimizeProblem& p_;
  mutable std::mutex mu_;
  std::unordered_map<std::vector<double>, std::shared_future<OptimizeCandidate>, Hash> map_;
  std::uint64_t hits_ = 0;
};

/// Distinct designs among candidates (their snapped values).
std::uint64_t distinct_designs(const std::vector<OptimizeCandidate>& all) {
  std::set<std::vector<double>> seen;
  for (const auto& c : all) seen.insert(c.x);
  return seen.size();
}

/// What an island remembers of its own evaluations (for the hybrid algorithm): every design, and
/// the non-dominated feasible ones with their fitness (kept up to date point by point).
struct IslandMemory {
  std::set<std::vector<double>> seen;
  std::vector<std::vector<double>> front_x, front_f;
  std::vector<std::vector<double>> all_x, all_f;  ///< every design of the island and its fitness
  std::vector<char> all_feasible;
  void add(const std::vector<double>& x, const std::vector<double>& f, bool feasible) {
    if (!seen.insert(x).second) return;
    all_x.push_back(x);
    all_f.push_back(f);
    all_feasible.push_back(feasible);
    if (!feasible) return;
    for (std::size_t k = 0; k < front_f.size(); ++k) {
      bool no_worse = true;
      for (std::size_t i = 0; i < f.size() && no_worse; ++i) no_worse = front_f[k][i] <= f[i];
      if (no_worse) return;  // dominated by (or equal to) a point of the front
    }
    for (std::size_t k = front_f.size(); k-- > 0;) {
      bool no_worse = true;
      for (std::size_t i = 0; i < f.size() && no_worse; ++i) no_worse = f[i] <= front_f[k][i];
      if (no_worse) {
        front_f.erase(front_f.begin() + std::ptrdiff_t(k));
        front_x.erase(front_x.begin() + std::ptrdiff_t(k));
      }
    }
    front_x.push_back(x);
    front_f.push_back(f);
  }
};

struct Udp {
  const OptimizeProblem* problem = nullptr;
  EvaluationCache* cache = nullptr;
  IslandMemory* memory = nullptr;  ///< the island's designs so far (the hybrid's)
  std::vector<OptimizeCandidate>* log = nullptr;
  int island = 0;
  std::uint32_t* round = nullptr;
  std::uint64_t* counter = nullptr;
  const Deadline* deadline = nullptr;

  pagmo::vector_double fitness(const pagmo::vector_double& x) const {
    if (deadline && deadline->passed()) throw Halt{};
    OptimizeCandidate c = cache ? cache->get(x) : problem->evaluate(x);
    c.island = island;
    c.round = *round;
    c.evaluation = ++*counter;
    const pagmo::vector_double f = problem->fitness(c);
    if (memory) memory->add(c.x, f, c.feasible());
    log->push_back(std::move(c));
    return f;
  }
  std::pair<pagmo::vector_double, pagmo::vector_double> get_bounds() const { return {problem->lower(), problem->upper()}; }
  pagmo::vector_double::size_type get_nobj() const { return problem->settings().objectives.size(); }
  std::string get_name() const { return "fivebar optimize"; }
  pagmo::thread_safety get_thread_safety() const { return pagmo::thread_safety::none; }
};

/// Runs work(k) for every island k on up to `threads` threads. An evaluation past the deadline
/// (Halt) makes it return true once every island has stopped; any other error is rethrown.
bool on_every_island(std::size_t n, int threads, const std::function<void(std::size_t)>& work) {
  std::vector<std::string> errors(n);
  std::vector<char> halted(n, 0);
#pragma omp parallel for schedule(dynamic, 1) num_threads(std::min<int>(threads, int(n)))
  for (std::size_t k = 0; k < n; ++k) {
    try {
      work(k);
    } catch (const Halt&) {
      halted[k] = 1;
    } catch (const std::exception& e) {
      errors[k] = e.what();
    }
  }
  for (const auto& e : errors) {
    if (!e.empty()) throw std::runtime_error("optimize: " + e);
  }
  return std::find(halted.begin(), halted.end(), 1) != halted.end();
}


/// The default algorithm for several objectives (docs/optimize.md "The hybrid algorithm"): NSGA-II's
/// elitist selection (non-dominated sorting and crowding over parents and children), with other
/// variation, a surrogate's pre-screening and no repeated design. Per child:
/// - with probability 0.25 (once the island's own front of feasible designs has 3 points), from a
///   point of that front (of at most 400 of its points, drawn at random) picked sparse-first (its nearest neighbour in the front's normalised
///   objectives far; the extremes of each objective first): a step toward that neighbour in design
///   space (filling the front's gaps), or a Gaussian step of 3 % of each range (refining it);
/// - otherwise a differential step around a tournament winner a of the population, a + F (b - c)
///   with two other members b, c (F uniform in [0.3, 0.9], crossover 0.9 per variable, at least
///   one): the steps shrink with the population's spread;
/// - then polynomial mutation (index 20, probability 1/n per variable);
/// - a child that snaps to a design this island has already evaluated (or to a member of the
///   population) is moved by a Gaussian step of growing width until it is new (at most 16 tries);
/// - eight such children are drawn and only one is evaluated: the one whose objectives, predicted
///   from its nearest neighbours among the island's latest 512 designs, are dominated by the fewest points of the
///   island's front (ties: the one farthest from every evaluated design). The prediction costs
///   microseconds, an evaluation (the certified coverage, the conditioning, the footprint) far more.
/// Everything is drawn from the round's seed: deterministic for a seed, whatever the thread count.
struct Hybrid {
  unsigned gens = 1;
  unsigned seed = 0;
  const OptimizeProblem* problem = nullptr;
  const IslandMemory* memory = nullptr;

  pagmo::population evolve(pagmo::population pop) const {
    const auto& prob = pop.get_problem();
    const std::size_t N = pop.size();
    if (N < 4 || gens == 0) return pop;
    // Not a structured binding: the lambdas below use the bounds, and clang 14 (the fuzz build)
    // refuses to capture a binding.
    const auto bounds = prob.get_bounds();
    const std::vector<double>& lo = bounds.first;
    const std::vector<double>& hi = bounds.second;
    const std::size_t n = lo.size();
    std::vector<double> inv_range(n);
    for (std::size_t d = 0; d < n; ++d) inv_range[d] = 1.0 / (hi[d] - lo[d]);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> U(0.0, 1.0);
    auto pick = [&](std::size_t k) { return std::size_t(rng() % k); };
    for (unsigned g = 0; g < gens; ++g) {
      const auto& X = pop.get_x();
      const auto& F = pop.get_f();
      // Position of each member in the NSGA-II order (rank, then crowding): a tournament's winner is the earlier.
      const std::vector<pagmo::pop_size_t> order = pagmo::sort_population_mo(F);
      std::vector<std::size_t> position(N);
      for (std::size_t i = 0; i < N; ++i) position[order[i]] = i;
      auto tournament = [&] {
        const std::size_t a = pick(N), b = pick(N);
        return position[a] < position[b] ? a : b;
      };
      std::set<std::vector<double>> taken(X.begin(), X.end());
      std::vector<pagmo::vector_double> xs = X, fs = F;
      // The island's front so far: each point's distance to its nearest neighbour in the front's
      // normalised objectives (the extremes of each objective: infinite), for a sparse-first pick.
      // (A copy: the evaluations of this generation change the island's front. At most kFrontSample
      // of its points, drawn at random, so that a generation costs a bounded time on a long run.)
      constexpr std::size_t kFrontSample = 400;
      std::vector<std::vector<double>> front_x, front_f;
      if (memory) {
        std::vector<std::size_t> idx(memory->front_x.size());
        for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = i;
        if (idx.size() > kFrontSample) {
          std::shuffle(idx.begin(), idx.end(), rng);
          idx.resize(kFrontSample);
          std::sort(idx.begin(), idx.end());
        }
        for (std::size_t i : idx) {
          front_x.push_back(memory->front_x[i]);
          front_f.push_back(memory->front_f[i]);
        }
      }
      const std::size_t A = front_x.size();
      std::vector<double> sparse(A, 0.0);
      std::vector<std::size_t> neighbour(A, 0);
      if (A >= 3) {
        const std::size_t m = front_f[0].size();
        std::vector<double> fmin(m, 1e300), fmax(m, -1e300);
        for (const auto& f : front_f) {
          for (std::size_t i = 0; i < m; ++i) fmin[i] = std::min(fmin[i], f[i]), fmax[i] = std::max(fmax[i], f[i]);
        }
        std::vector<double> unit(A * m);  // the front's objectives scaled to [0, 1]
        for (std::size_t k = 0; k < A; ++k) {
          for (std::size_t i = 0; i < m; ++i) unit[k * m + i] = (front_f[k][i] - fmin[i]) / (fmax[i] > fmin[i] ? fmax[i] - fmin[i] : 1.0);
        }
        for (std::size_t k = 0; k < A; ++k) {
          double best = std::numeric_limits<double>::infinity();
          for (std::size_t l = 0; l < A; ++l) {
            if (l == k) continue;
            double d2 = 0.0;
            for (std::size_t i = 0; i < m; ++i) {
              const double t = unit[k * m + i] - unit[l * m + i];
              d2 += t * t;
            }
            if (d2 < best) best = d2, neighbour[k] = l;
          }
          sparse[k] = best;
          for (std::size_t i = 0; i < m; ++i) {
            if (front_f[k][i] == fmin[i]) sparse[k] = std::numeric_limits<double>::infinity();
          }
        }
      }
      auto sparse_pick = [&] {
        const std::size_t a = pick(A), b = pick(A);
        return sparse[a] >= sparse[b] ? a : b;
      };
      auto make_child = [&] {
        std::vector<double> y(n);
        const std::size_t a = tournament();
        const double op = U(rng);
        if (A >= 3 && op < 0.25) {
          // From the island's front: a step toward the nearest neighbour in objective space (filling
          // the front's gaps), or a small local step (refining it).
          const std::size_t k = sparse_pick();
          const auto& xa = front_x[k];
          const auto& xb = front_x[neighbour[k]];
          const bool toward = U(rng) < 0.5;
          const double u = U(rng);
          std::normal_distribution<double> noise(0.0, toward ? 0.01 : 0.03);
          for (std::size_t d = 0; d < n; ++d) {
            const double base = toward ? xa[d] + u * (xb[d] - xa[d]) : xa[d];
            y[d] = std::clamp(base + noise(rng) * (hi[d] - lo[d]), lo[d], hi[d]);
          }
        } else {
          std::size_t b = pick(N), c = pick(N);
          while (b == a) b = pick(N);
          while (c == a || c == b) c = pick(N);
          const double f = 0.3 + 0.6 * U(rng);
          const std::size_t forced = pick(n);
          for (std::size_t d = 0; d < n; ++d) {
            y[d] = (d == forced || U(rng) < 0.9) ? X[a][d] + f * (X[b][d] - X[c][d]) : X[a][d];
            // Out of the box: half way from the parent to the bound it crossed.
            if (y[d] < lo[d]) y[d] = 0.5 * (X[a][d] + lo[d]);
            if (y[d] > hi[d]) y[d] = 0.5 * (X[a][d] + hi[d]);
          }
        }
        for (std::size_t d = 0; d < n; ++d) {
          if (U(rng) >= 1.0 / double(n)) continue;
          const double u = U(rng), range = hi[d] - lo[d];
          const double delta = u < 0.5 ? std::pow(2.0 * u, 1.0 / 21.0) - 1.0 : 1.0 - std::pow(2.0 * (1.0 - u), 1.0 / 21.0);
          y[d] = std::clamp(y[d] + delta * range, lo[d], hi[d]);
        }
        return y;
      };
      // The surrogate: the objectives of a design predicted from its nearest evaluated neighbours on
      // the island (inverse-distance weights over the 4 nearest of its latest 512 designs, in the
      // box's normalised coordinates; infeasible when the nearest is). Of kChoices children the one predicted to be
      // dominated by the fewest points of the island's front is evaluated (ties: the farthest from
      // every evaluated design).
      constexpr int kChoices = 8;
      auto score = [&](const std::vector<double>& x, double& far) {
        constexpr std::size_t kNear = 4;
        std::vector<std::pair<double, std::size_t>> near;
        const auto& ax = memory->all_x;
        // The island's latest kWindow designs only (they surround the population): a bounded cost.
        constexpr std::size_t kWindow = 512;
        for (std::size_t i = ax.size() > kWindow ? ax.size() - kWindow : 0; i < ax.size(); ++i) {
          double d2 = 0.0;
          for (std::size_t d = 0; d < n; ++d) {
            const double t = (x[d] - ax[i][d]) * inv_range[d];
            d2 += t * t;
          }
          if (near.size() < kNear || d2 < near.back().first) {
            near.emplace_back(d2, i);
            std::sort(near.begin(), near.end());
            if (near.size() > kNear) near.pop_back();
          }
        }
        far = near.empty() ? 0.0 : near.front().first;
        if (near.empty()) return 0.0;
        const auto& af = memory->all_f;
        if (!memory->all_feasible[near.front().second]) return double(A) + 1.0;
        const std::size_t m = af[0].size();
        std::vector<double> f(m, 0.0);
        double wsum = 0.0;
        for (const auto& [d2, i] : near) {
          if (!memory->all_feasible[i]) continue;
          const double w = 1.0 / (d2 + 1e-12);
          wsum += w;
          for (std::size_t k = 0; k < m; ++k) f[k] += w * af[i][k];
        }
        for (auto& v : f) v /= wsum;
        double dominated_by = 0.0;
        for (const auto& q : front_f) {
          bool no_worse = true;
          for (std::size_t k = 0; k < m && no_worse; ++k) no_worse = q[k] <= f[k];
          dominated_by += no_worse;
        }
        return dominated_by;
      };
      for (std::size_t child = 0; child < N; ++child) {
        std::vector<double> key;
        double best_score = 0.0, best_far = 0.0;
        const int choices = (memory && memory->all_x.size() >= 2 * n + 2) ? kChoices : 1;
        for (int choice = 0; choice < choices; ++choice) {
          std::vector<double> y = make_child();
          std::vector<double> cand = problem->snap(y);
          for (int attempt = 1; attempt <= 16 && (taken.count(cand) || (memory && memory->seen.count(cand))); ++attempt) {
            std::normal_distribution<double> step(0.0, 0.02 * attempt);
            for (std::size_t d = 0; d < n; ++d) y[d] = std::clamp(cand[d] + step(rng) * (hi[d] - lo[d]), lo[d], hi[d]);
            cand = problem->snap(y);
          }
          if (choices == 1) {
            key = std::move(cand);
            break;
          }
          double far = 0.0;
          const double sc = score(cand, far);
          if (key.empty() || sc < best_score || (sc == best_score && far > best_far)) {
            best_score = sc;
            best_far = far;
            key = std::move(cand);
          }
        }
        taken.insert(key);
        fs.push_back(prob.fitness(key));
        xs.push_back(std::move(key));
      }
      const std::vector<pagmo::pop_size_t> best = pagmo::select_best_N_mo(fs, N);
      for (std::size_t i = 0; i < N; ++i) pop.set_xf(i, xs[best[i]], fs[best[i]]);
    }
    return pop;
  }
  std::string get_name() const { return "hybrid"; }
};

/// The hybrid's initial population of an island: on island 0 the design as given (most often a
/// covering design, when random points of a wide box rarely cover), then a Latin hypercube of the
/// box (every variable's range cut in `count` strata, one point in each), drawn from `seed`.
std::vector<std::vector<double>> hybrid_start(const OptimizeProblem& p, std::size_t count, int island, unsigned seed) {
  const std::size_t n = p.dimension();
  const auto lo = p.lower(), hi = p.upper();
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::vector<std::vector<double>> xs(count, std::vector<double>(n));
  for (std::size_t d = 0; d < n; ++d) {
    std::vector<std::size_t> strata(count);
    for (std::size_t i = 0; i < count; ++i) strata[i] = i;
    std::shuffle(strata.begin(), strata.end(), rng);
    for (std::size_t i = 0; i < count; ++i) xs[i][d] = lo[d] + (hi[d] - lo[d]) * (double(strata[i]) + U(rng)) / double(count);
  }
  if (island == 0 && count > 0) xs[0] = p.snap(p.reference_values());
  return xs;
}

/// Deb's recommended NSGA-II operators: crossover probability 0.9, distribution indices 20, and a
/// mutation probability of 1/n per variable (pagmo's default 0.01 barely mutates a problem of a
/// few variables).
pagmo::algorithm make_algorithm(const std::string& name, unsigned gens, unsigned seed, int population, std::size_t n,
                                std::size_t nobj, const OptimizeProblem* problem = nullptr,
                                const IslandMemory* memory = nullptr) {
  if (name == "hybrid") return pagmo::algorithm(Hybrid{gens, seed, problem, memory});
  if (name == "nsga2") return pagmo::algorithm(pagmo::nsga2(gens, 0.9, 20.0, 1.0 / double(std::max<std::size_t>(n, 1)), 20.0, seed));
  if (name == "moead") {
    // Grid weights need a population of a binomial size beyond two objectives: low-discrepancy ones there.
    return pagmo::algorithm(pagmo::moead(gens, nobj > 2 ? "low discrepancy" : "grid", "tchebycheff", std::min<unsigned>(20u, unsigned(population - 1)), 1.0, 0.5,
                                         20.0, 0.9, 2u, true, seed));
  }
  if (name == "cmaes") return pagmo::algorithm(pagmo::cmaes(gens, -1, -1, -1, -1, 0.3, 1e-9, 1e-9, false, true, seed));
  return pagmo::algorithm(pagmo::sade(gens, 2u, 1u, 1e-9, 1e-9, false, seed));
}

Json opt(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }
double num_or_nan(const Json& j) { return j.is_number() ? j.get<double>() : kNaN; }

Json candidate_json(const OptimizeCandidate& c) {
  Json figures = Json::array();
  for (double f : c.figures) figures.push_back(opt(f));
  return Json{{"x", c.x}, {"figures", figures}, {"verdict", to_string(c.verdict)}, {"status", c.status},
              {"violation", c.violation}, {"island", c.island}, {"round", c.round}, {"evaluation", c.evaluation}};
}

OptimizeCandidate candidate_from(const Json& j) {
  OptimizeCandidate c;
  c.x = j.at("x").get<std::vector<double>>();
  for (const Json& f : j.at("figures")) c.figures.push_back(num_or_nan(f));
  const std::string v = j.at("verdict").get<std::string>();
  for (OptimizeVerdict k : {OptimizeVerdict::invalid, OptimizeVerdict::not_covered, OptimizeVerdict::cheap_constraint,
                            OptimizeVerdict::loop_constraint, OptimizeVerdict::simulation_constraint, OptimizeVerdict::feasible}) {
    if (v == to_string(k)) c.verdict = k;
  }
  c.status = j.at("status").get<std::string>();
  c.violation = j.at("violation").get<double>();
  c.island = j.at("island").get<int>();
  c.round = j.at("round").get<std::uint32_t>();
  c.evaluation = j.at("evaluation").get<std::uint64_t>();
  return c;
}

/// The run's identity: a checkpoint or shard file of another design (or other settings) is refused.
std::string design_hash(const OptimizeProblem& p) {
  Design d = p.design();
  d.set(p.settings());
  char buf[24];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(format::fnv1a64(to_yaml(d))));
  return std::string("fnv1a64:") + buf;
}

std::string shard_suffix(std::uint64_t k, std::uint64_t n) {
  return n > 1 ? ".shard-" + std::to_string(k) + "-of-" + std::to_string(n) : "";
}

/// Ideal and nadir of the front (fitness, to minimise).
void normalisation(const OptimizeProblem& p, const std::vector<OptimizeCandidate>& front, std::vector<double>& ideal,
                   std::vector<double>& nadir) {
  const std::size_t m = p.settings().objectives.size();
  ideal.assign(m, std::numeric_limits<double>::infinity());
  nadir.assign(m, -std::numeric_limits<double>::infinity());
  for (const auto& c : front) {
    const auto f = p.fitness(c);
    for (std::size_t i = 0; i < m; ++i) {
      ideal[i] = std::min(ideal[i], f[i]);
      nadir[i] = std::max(nadir[i], f[i]);
    }
  }
}

/// The hypervolume after each round: the front of the candidates of rounds <= r, normalised by
/// the final front's ideal and nadir, against the reference point 1.1 in every objective.
std::vector<std::pair<std::uint64_t, double>> hypervolume_curve(const OptimizeProblem& p,
                                                                const std::vector<OptimizeCandidate>& all,
                                                                const std::vector<double>& ideal,
                                                                const std::vector<double>& nadir) {
  std::vector<std::pair<std::uint64_t, double>> curve;
  std::uint32_t last = 0;
  for (const auto& c : all) last = std::max(last, c.round);
  std::vector<OptimizeCandidate> upto;
  const std::vector<double> reference(p.settings().objectives.size(), 1.1);
  std::uint64_t count = 0;
  for (std::uint32_t r = 0; r <= last; ++r) {
    for (const auto& c : all) {
      if (c.round != r) continue;
      ++count;
      if (c.feasible()) upto.push_back(c);
    }
    upto = optimize_front(p, upto);
    curve.emplace_back(count, hypervolume(normalised_objectives(p, upto, ideal, nadir), reference));
  }
  return curve;
}

/// The chosen point of the front (settings.choose).
std::size_t choose(const OptimizeProblem& p, const std::vector<OptimizeCandidate>& front, const std::vector<double>& ideal,
                   const std::vector<double>& nadir) {
  const auto& s = p.settings();
  std::size_t best = 0;
  double best_v = std::numeric_limits<double>::infinity();
  const auto norm = normalised_objectives(p, front, ideal, nadir);
  int objective = -1;
  for (std::size_t i = 0; i < s.objectives.size(); ++i) {
    if (s.objectives[i].figure == s.choose) objective = int(i);
  }
  for (std::size_t k = 0; k < front.size(); ++k) {
    double v = 0.0;
    if (objective >= 0) {
      v = norm[k][std::size_t(objective)];
    } else {
      for (double f : norm[k]) v += f * f;  // knee: nearest the ideal point
    }
    if (v < best_v) {
      best_v = v;
      best = k;
    }
  }
  return best;
}

/// COBYLA from the chosen point: minimise the sum of the normalised objectives subject to
/// feasibility and to every objective no worse than the chosen point's, so that the result is
/// feasible and dominates (or equals) the chosen design.
std::optional<OptimizeCandidate> polish(const OptimizeProblem& p, EvaluationCache& cache, const OptimizeCandidate& start, const std::vector<double>& ideal,
                                        const std::vector<double>& nadir, std::uint64_t budget, double seconds,
                                        const std::atomic<bool>* stop, std::uint64_t& used) {
  const std::size_t n = p.dimension(), m = p.settings().objectives.size();
  if (budget == 0 || n == 0 || !(seconds > 0.0) || (stop && stop->load())) return std::nullopt;
  const auto f0 = p.fitness(start);
  std::vector<double> scale(m);
  for (std::size_t i = 0; i < m; ++i) scale[i] = nadir[i] > ideal[i] ? nadir[i] - ideal[i] : 1.0;
  struct State {
    const OptimizeProblem* p;
    EvaluationCache* cache;
    std::vector<double> last_x;
    OptimizeCandidate last;
    std::optional<OptimizeCandidate> best;
    double best_value = std::numeric_limits<double>::infinity();
    std::uint64_t evaluations = 0;
    std::vector<double> f0, scale;
    const OptimizeCandidate& at(const std::vector<double>& x) {
      if (x != last_x || last.x.empty()) {
        last = cache->get(x);
        last_x = x;
        ++evaluations;
        if (last.feasible()) {
          const auto f = p->fitness(last);
          bool no_worse = true;
          double v = 0.0;
          for (std::size_t i = 0; i < f.size(); ++i) {
            no_worse = no_worse && f[i] <= f0[i];
            v += f[i] / scale[i];
          }
          if (no_worse && v < best_value) {
            best_value = v;
            best = last;
          }
        }
      }
      return last;
    }
  } st{&p, &cache, {}, {}, std::nullopt, std::numeric_limits<double>::infinity(), 0, f0, scale};
  nlopt::opt o(nlopt::LN_COBYLA, unsigned(n));
  o.set_lower_bounds(p.lower());
  o.set_upper_bounds(p.upper());
  std::vector<double> step(n);
  for (std::size_t d = 0; d < n; ++d) step[d] = 0.05 * (p.upper()[d] - p.lower()[d]);
  o.set_initial_step(step);
  o.set_maxeval(int(std::min<std::uint64_t>(budget, 1000000)));
  o.set_xtol_rel(1e-6);
  o.set_maxtime(seconds);
  o.set_min_objective(
      [](const std::vector<double>& x, std::vector<double>&, void* data) {
        State& s = *static_cast<State*>(data);
        const OptimizeCandidate& c = s.at(x);
        const auto f = s.p->fitness(c);
        double v = 0.0;
        for (std::size_t i = 0; i < f.size(); ++i) v += (c.feasible() ? f[i] : s.f0[i] + 1.0) / s.scale[i];
        return v;
      },
      &st);
  o.add_inequality_constraint(
      [](const std::vector<double>& x, std::vector<double>&, void* data) {
        State& s = *static_cast<State*>(data);
        const OptimizeCandidate& c = s.at(x);
        return c.feasible() ? 0.0 : 1.0 + std::min(c.violation, 1e6);
      },
      &st, 0.0);
  // Objectives no worse than the chosen point's: one constraint for all (the largest excess).
  o.add_inequality_constraint(
      [](const std::vector<double>& x, std::vector<double>&, void* data) {
        State& s = *static_cast<State*>(data);
        const OptimizeCandidate& c = s.at(x);
        if (!c.feasible()) return 1.0;
        const auto f = s.p->fitness(c);
        double worst = -std::numeric_limits<double>::infinity();
        for (std::size_t i = 0; i < f.size(); ++i) worst = std::max(worst, (f[i] - s.f0[i]) / s.scale[i]);
        return worst;
      },
      &st, 0.0);
  std::vector<double> x = start.x;
  double value = 0.0;
  try {
    o.optimize(x, value);
  } catch (const nlopt::roundoff_limited&) {
  } catch (const nlopt::forced_stop&) {
  } catch (const std::runtime_error&) {  // NLopt's generic failure: the best point so far stands
  }
  used = st.evaluations;
  if (!st.best) return std::nullopt;
  // Only a strict improvement of the sum counts.
  double start_value = 0.0;
  for (std::size_t i = 0; i < m; ++i) start_value += f0[i] / scale[i];
  if (!(st.best_value < start_value - 1e-12)) return std::nullopt;
  return st.best;
}

using csv::field;
std::string cell(double v) { return csv::number(v); }

std::string csv_header(const OptimizeProblem& p, bool with_status) {
  std::string h = "island,round,evaluation";
  for (const auto& v : p.settings().variables) h += "," + field(v.name);
  for (const auto& f : optimize_figures()) h += "," + std::string(f.name);
  if (with_status) h += ",verdict,status";
  return h + "\n";
}
std::string csv_row(const OptimizeCandidate& c, bool with_status) {
  std::string r = std::to_string(c.island) + "," + std::to_string(c.round) + "," + std::to_string(c.evaluation);
  for (double x : c.x) r += "," + cell(x);
  for (double f : c.figures) r += "," + cell(f);
  if (with_status) r += std::string(",") + to_string(c.verdict) + "," + field(c.status);
  return r + "\n";
}

/// A population's individuals, best first: pagmo's non-dominated sorting (crowding distance within a
/// front) for several objectives, the fitness for one.
std::vector<pagmo::pop_size_t> best_first(const std::vector<pagmo::vector_double>& f) {
  if (!f.empty() && f.front().size() > 1) return pagmo::sort_population_mo(f);
  std::vector<pagmo::pop_size_t> order(f.size());
  for (std::size_t i = 0; i < f.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](auto a, auto b) { return f[a][0] < f[b][0]; });
  return order;
}

/// Order of candidates in files: by round, island, evaluation (the same for any thread count).
void sort_candidates(std::vector<OptimizeCandidate>& all) {
  std::stable_sort(all.begin(), all.end(), [](const OptimizeCandidate& a, const OptimizeCandidate& b) {
    if (a.round != b.round) return a.round < b.round;
    if (a.island != b.island) return a.island < b.island;
    return a.evaluation < b.evaluation;
  });
}

/// Everything after the search: front, curve, choice, polish, files.
OptimizeResult finish(const OptimizeProblem& p, EvaluationCache& cache, const Design& design, std::vector<OptimizeCandidate> all,
                      const OptimizeOptions& options, OptimizeResult r, bool whole_run, double polish_seconds) {
  // polish_seconds: what is left of the wall-time budget, for the polish and the full figures.
  sort_candidates(all);
  r.stages = {};
  for (const auto& c : all) r.stages.add(c);
  r.evaluations = all.size();
  r.distinct = distinct_designs(all);
  r.cache_hits = cache.hits();
  r.front = optimize_front(p, all);
  normalisation(p, r.front, r.ideal, r.nadir);
  // A front of one value in an objective (always so for one objective): its nadir is the worst
  // feasible candidate's instead, so the curve still shows the progress.
  for (std::size_t i = 0; i < r.ideal.size(); ++i) {
    if (r.nadir[i] > r.ideal[i]) continue;
    for (const auto& c : all) {
      if (c.feasible()) r.nadir[i] = std::max(r.nadir[i], p.fitness(c)[i]);
    }
  }
  r.hypervolume = hypervolume_curve(p, all, r.ideal, r.nadir);
  r.reference = cache.get(p.reference_values());
  const std::filesystem::path& dir = options.out_dir;
  make_directories(dir);
  auto record = [&](const std::filesystem::path& f) { r.files.push_back(f); };
  if (!whole_run) {
    Json shard{{"format", kShardFormat}, {"design_hash", design_hash(p)}, {"shard", options.shard},
               {"shards", options.shards}, {"seconds", r.seconds}, {"rounds", r.rounds},
               {"interrupted", r.interrupted}, {"candidate_count", all.size()}, {"candidates", Json::array()}};
    for (const auto& c : all) shard["candidates"].push_back(candidate_json(c));
    const auto path = dir / ("front" + shard_suffix(options.shard, options.shards) + ".json");
    write_file_atomic(path, shard.dump() + "\n");
    record(path);
    return r;
  }
  if (!r.front.empty()) {
    r.chosen = r.front[choose(p, r.front, r.ideal, r.nadir)];
    if (p.settings().polish) {
      r.polished = polish(p, cache, *r.chosen, r.ideal, r.nadir, p.settings().polish_evaluations, polish_seconds, options.stop,
                          r.polish_evaluations);
    }
    r.cache_hits = cache.hits();
    const OptimizeCandidate& best = r.polished ? *r.polished : *r.chosen;
    Design chosen = p.design_at(best.x);
    std::string name = design.name + "-optimized";
    if (name.size() > 64) name = design.name.substr(0, 54) + "-optimized";
    chosen.name = name;
    chosen.products.reset();
    r.chosen_design = chosen;
    // Every figure of the design as given and of the chosen one, for the comparison table (the
    // loop and the simulations included: seconds), when the wall-time budget has some left.
    if (options.full_figures && polish_seconds > 0.0 && !(options.stop && options.stop->load())) {
      const OptimizeProblem full(design, every_figure_settings(design, p.settings()));
      r.reference_full = full.evaluate(p.reference_values());
      r.chosen_full = full.evaluate(best.x);
    }
    const auto yaml = dir / "chosen.yaml";
    std::string header = "# The design chosen by `fivebar optimize` from " +
                         (design.source.empty() ? std::string("design '") + design.name + "'" : design.source.filename().string()) +
                         " (" + p.settings().choose + " of the front" + (r.polished ? ", polished by COBYLA" : "") +
                         "): a complete design file;\n# its optimize: and sweep: sections are left out. Run it with `fivebar run`.\n";
    write_file_atomic(yaml, header + to_yaml(chosen));
    record(yaml);
  }
  if (p.settings().atlas && r.chosen_design) {
    // The family of each optimised station, with the design as given and the chosen one marked.
    for (const std::string& name : p.stations()) {
      const Station& given = *design.station(name);
      AtlasOptions ao;
      ao.cells = p.settings().atlas_cells;
      ao.threads = options.threads;
      Atlas atlas = performance_atlas(given, ao);
      const Station* chosen_station = r.chosen_design->station(name);
      if (chosen_station) {
        const Mechanism* m = chosen_station->lower ? &*chosen_station->lower : chosen_station->upper ? &*chosen_station->upper : nullptr;
        if (m) (void)add_mark(atlas, "chosen", *m);
      }
      for (const auto& f : write_atlas_files(dir, atlas, "atlas-" + name, "station " + name + " of " + design.name)) record(f);
      r.atlases.push_back(Json{{"station", name}, {"atlas", to_json(atlas)}});
    }
  }
  {
    const auto path = dir / "front.csv";
    std::string text = csv_header(p, false);
    for (const auto& c : r.front) text += csv_row(c, false);
    write_file_atomic(path, text);
    record(path);
  }
  {
    const auto path = dir / "candidates.csv";
    AtomicFile f(path);
    f.stream() << csv_header(p, true);
    for (const auto& c : all) f.stream() << csv_row(c, true);
    f.commit();
    record(path);
  }
  {
    const auto path = dir / "front.json";
    write_file_atomic(path, r.to_json(p).dump(2) + "\n");
    record(path);
  }
  if (options.plots && !r.front.empty()) {
    const std::string title = "fivebar optimize: " + design.name + " (" + r.algorithm + ", " +
                              std::to_string(p.settings().islands) + " islands)";
    const RenderedPlot hv = detail::hypervolume_plot(r.hypervolume, title);
    write_file_atomic(dir / "hypervolume.svg", hv.svg);
    write_file_atomic(dir / "hypervolume.png", hv.png);
    record(dir / "hypervolume.svg");
    record(dir / "hypervolume.png");
    std::vector<detail::ParallelAxis> axes;
    const auto& vars = p.settings().variables;
    for (const auto& v : vars) axes.push_back({v.name, v.lo, v.hi});
    std::vector<std::size_t> objective_index;
    for (const auto& o : p.settings().objectives) {
      const std::size_t i = std::size_t(optimize_figure_index(o.figure));
      objective_index.push_back(i);
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      for (const auto& c : r.front) {
        lo = std::min(lo, c.figures[i]);
        hi = std::max(hi, c.figures[i]);
      }
      const double ref = r.reference.figures[i];
      if (std::isfinite(ref)) {
        lo = std::min(lo, ref);
        hi = std::max(hi, ref);
      }
      const auto& f = optimize_figures()[i];
      axes.push_back({std::string(f.name) + (f.unit.empty() ? "" : " (" + std::string(f.unit) + ")") +
                          (o.maximise ? " max" : " min"),
                      lo, hi});
    }
    std::vector<std::vector<double>> rows;
    int chosen_row = -1;
    auto row_of = [&](const OptimizeCandidate& c) {
      std::vector<double> row = c.x;
      for (std::size_t i : objective_index) row.push_back(c.figures.size() > i ? c.figures[i] : kNaN);
      return row;
    };
    for (const auto& c : r.front) rows.push_back(row_of(c));
    if (r.chosen) {
      rows.push_back(row_of(r.polished ? *r.polished : *r.chosen));
      chosen_row = int(rows.size() - 1);
    }
    const RenderedPlot pc = detail::parallel_coordinates_plot(axes, rows, chosen_row, row_of(r.reference),
                                                              "Pareto front of " + design.name + " in parallel coordinates (colour: first objective)",
                                                              vars.size());
    write_file_atomic(dir / "front.svg", pc.svg);
    write_file_atomic(dir / "front.png", pc.png);
    record(dir / "front.svg");
    record(dir / "front.png");
  }
  return r;
}

Json checkpoint_json(const OptimizeProblem& p, const OptimizeOptions& o, std::uint32_t round, double seconds,
                     const std::vector<int>& islands, const std::vector<pagmo::population>& pops,
                     const std::vector<OptimizeCandidate>& all) {
  Json j{{"format", kCheckpointFormat}, {"design_hash", design_hash(p)}, {"shard", o.shard}, {"shards", o.shards},
         {"round", round}, {"seconds", seconds}, {"islands", Json::array()}, {"candidates", Json::array()}};
  for (std::size_t k = 0; k < islands.size(); ++k) {
    j["islands"].push_back(Json{{"island", islands[k]}, {"x", pops[k].get_x()}, {"f", pops[k].get_f()}});
  }
  for (const auto& c : all) j["candidates"].push_back(candidate_json(c));
  return j;
}

}  // namespace

double hypervolume(const std::vector<std::vector<double>>& points, const std::vector<double>& reference) {
  std::vector<std::vector<double>> inside;
  for (const auto& q : points) {
    bool ok = q.size() == reference.size();
    for (std::size_t i = 0; ok && i < q.size(); ++i) ok = std::isfinite(q[i]) && q[i] < reference[i];
    if (ok) inside.push_back(q);
  }
  if (inside.empty()) return 0.0;
  if (reference.size() == 1) {
    double best = reference[0];
    for (const auto& q : inside) best = std::min(best, q[0]);
    return reference[0] - best;
  }
  return pagmo::hypervolume(inside, false).compute(reference);
}

OptimizeResult run_optimize(const Design& design, const OptimizeOptions& options) {
  const OptimizeProblem p(design);
  const OptimizeSettings& s = p.settings();
  if (options.shards == 0 || options.shard >= options.shards) {
    throw InputError("optimize: shard " + std::to_string(options.shard) + " of " + std::to_string(options.shards) +
                     " does not exist (shards are numbered 0 ... N-1)");
  }
  if (options.shards > std::uint64_t(s.islands)) {
    throw InputError("optimize: " + std::to_string(options.shards) + " shards for " + std::to_string(s.islands) +
                     " islands (optimize.islands): every shard runs at least one island");
  }
  const int threads = sweep_threads(options.threads);
  const auto t0 = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };

  std::vector<int> islands;  // this shard's
  for (int i = 0; i < s.islands; ++i) {
    if (std::uint64_t(i) % options.shards == options.shard) islands.push_back(i);
  }
  const std::uint64_t total_budget = options.evaluations ? options.evaluations : s.evaluations;
  const std::uint64_t budget = std::max<std::uint64_t>(1, total_budget * islands.size() / std::uint64_t(s.islands));
  if (total_budget < std::uint64_t(s.population) * std::uint64_t(s.islands)) {
    throw InputError("optimize: a budget of " + std::to_string(total_budget) + " evaluations is less than the initial populations (" +
                     std::to_string(s.population) + " x " + std::to_string(s.islands) + " islands)");
  }
  const double seconds_budget = options.seconds > 0.0 ? options.seconds : s.seconds;
  const std::string alg = s.resolved_algorithm();
  const auto checkpoint = options.out_dir / ("checkpoint" + shard_suffix(options.shard, options.shards) + ".json");

  // Per island: its log, counters and population.
  const std::size_t n = islands.size();
  std::vector<std::vector<OptimizeCandidate>> logs(n);
  std::vector<std::uint64_t> counters(n, 0);
  std::vector<std::uint32_t> rounds(n, 0);
  std::vector<IslandMemory> memory(n);  // per island: its designs so far
  std::vector<pagmo::population> pops;
  std::vector<OptimizeCandidate> all;
  std::uint32_t round = 0;
  double prior_seconds = 0.0;
  auto span = [](double seconds) {
    return std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(seconds));
  };
  Deadline deadline{t0 + span(seconds_budget), options.stop};
  EvaluationCache cache(p);
  auto problem_of = [&](std::size_t k) {
    return pagmo::problem(Udp{&p, &cache, &memory[k], &logs[k], islands[k], &rounds[k], &counters[k], &deadline});
  };

  if (options.resume) {
    std::error_code ec;
    if (!std::filesystem::exists(checkpoint, ec)) throw InputError(checkpoint.string() + ": no checkpoint to resume from");
    const Json j = read_optimize_file(checkpoint, "checkpoint");
    if (j.value("format", "") != kCheckpointFormat) throw InputError(checkpoint.string() + ": not a checkpoint of fivebar optimize");
    if (j.value("design_hash", "") != design_hash(p)) {
      throw InputError(checkpoint.string() + ": the checkpoint is of another design or other optimize: settings");
    }
    // Identity and sizes before use (docs/reliability.md): the shard, every island's number and
    // population size, and every individual's dimension and fitness length.
    auto damaged = [&](const std::string& what) { return InputError(checkpoint.string() + ": " + what); };
    try {
      if (j.at("shard").get<std::uint64_t>() != options.shard || j.at("shards").get<std::uint64_t>() != options.shards) {
        throw damaged("holds shard " + std::to_string(j.at("shard").get<std::uint64_t>()) + " of " +
                      std::to_string(j.at("shards").get<std::uint64_t>()) + ", not shard " + std::to_string(options.shard) +
                      " of " + std::to_string(options.shards));
      }
      round = j.at("round").get<std::uint32_t>();
      prior_seconds = j.at("seconds").get<double>();
      if (!std::isfinite(prior_seconds) || prior_seconds < 0.0) throw damaged("seconds must be a finite number >= 0");
      deadline.end -= span(std::min(prior_seconds, seconds_budget));
      for (const Json& c : j.at("candidates")) {
        OptimizeCandidate cand = candidate_from(c);
        if (cand.x.size() != p.dimension() || cand.figures.size() != optimize_figures().size()) {
          throw damaged("a candidate with " + std::to_string(cand.x.size()) + " values and " + std::to_string(cand.figures.size()) +
                        " figures (the design has " + std::to_string(p.dimension()) + " variables)");
        }
        all.push_back(std::move(cand));
      }
      const Json& isl = j.at("islands");
      if (isl.size() != n) {
        throw damaged(std::to_string(isl.size()) + " islands, this shard runs " + std::to_string(n));
      }
      const std::size_t objectives = s.objectives.size();
      for (std::size_t k = 0; k < n; ++k) {
        if (isl[k].at("island").get<int>() != islands[k]) {
          throw damaged("island " + std::to_string(isl[k].at("island").get<int>()) + " where island " + std::to_string(islands[k]) +
                        " belongs");
        }
        pagmo::population pop(problem_of(k), 0u, seed32(s.seed, std::uint64_t(islands[k]), 0));
        const auto xs = isl[k].at("x").get<std::vector<std::vector<double>>>();
        const auto fs = isl[k].at("f").get<std::vector<std::vector<double>>>();
        if (xs.size() != std::size_t(s.population) || fs.size() != xs.size()) {
          throw damaged("island " + std::to_string(islands[k]) + " holds " + std::to_string(xs.size()) + " individuals and " +
                        std::to_string(fs.size()) + " fitness vectors, the population is " + std::to_string(s.population));
        }
        for (std::size_t i = 0; i < xs.size(); ++i) {
          if (xs[i].size() != p.dimension() || fs[i].size() != objectives) {
            throw damaged("island " + std::to_string(islands[k]) + ", individual " + std::to_string(i) + ": " +
                          std::to_string(xs[i].size()) + " values and " + std::to_string(fs[i].size()) +
                          " fitness values (the design has " + std::to_string(p.dimension()) + " variables and " +
                          std::to_string(objectives) + " objectives)");
          }
          pop.push_back(xs[i], fs[i]);
        }
        pops.push_back(std::move(pop));
      }
    } catch (const InputError&) {
      throw;
    } catch (const std::exception& e) {
      throw InputError(checkpoint.string() + ": a damaged checkpoint (" + e.what() + ")");
    }
    for (const auto& c : all) {
      cache.insert(c);
      for (std::size_t k = 0; k < n; ++k) {
        if (c.island == islands[k]) memory[k].add(c.x, p.fitness(c), c.feasible());
        if (c.island == islands[k]) counters[k] = std::max(counters[k], c.evaluation);
      }
    }
  } else {
    pops.resize(n);
    const bool halted = on_every_island(n, threads, [&](std::size_t k) {
      if (alg == "hybrid") {
        pops[k] = pagmo::population(problem_of(k), 0u, seed32(s.seed, std::uint64_t(islands[k]), 0));
        for (auto& x : hybrid_start(p, std::size_t(s.population), islands[k], seed32(s.seed, std::uint64_t(islands[k]), 0))) {
          pops[k].push_back(x);
        }
      } else {
        pops[k] = pagmo::population(problem_of(k), pagmo::population::size_type(s.population),
                                    seed32(s.seed, std::uint64_t(islands[k]), 0));
      }
    });
    for (auto& l : logs) {
      all.insert(all.end(), l.begin(), l.end());
      l.clear();
    }
    if (halted) {
      // Stopped before every island had its first population: the candidates so far are the
      // result, and there is no state to resume from.
      if (!(options.stop && options.stop->load())) {
        throw InputError("optimize: the wall-time budget (optimize.seconds: " + format::shortest(seconds_budget) +
                             " s) ran out before the initial populations were evaluated",
                         Remedy::longer_budget);
      }
      OptimizeResult r;
      r.algorithm = alg;
      r.interrupted = true;
      r.seconds = elapsed();
      return finish(p, cache, design, std::move(all), options, r, options.shards == 1, 0.0);
    }
  }
  // Every input checked (the checkpoint too): only now is anything created (docs/reliability.md).
  make_directories(options.out_dir);
  // pagmo's populations hold their own copies of the problem: point them at this run's logs.
  // (A population built above already does; after a resume the same.)

  OptimizeResult r;
  r.algorithm = alg;
  auto front_size = [&] { return optimize_front(p, all).size(); };
  double checkpoint_at = 0.0, checkpoint_cost = 0.0;  // when the last was written, and how long it took
  std::uint32_t checkpoint_round = round;
  auto write_checkpoint = [&] {
    const double start = elapsed();
    write_file_atomic(checkpoint, checkpoint_json(p, options, round, prior_seconds + start, islands, pops, all).dump() + "\n");
    checkpoint_at = elapsed();
    checkpoint_cost = checkpoint_at - start;
    checkpoint_round = round;
  };
  if (options.progress) options.progress(all.size(), budget, prior_seconds + elapsed(), front_size());
  const std::uint64_t per_generation = std::uint64_t(s.population) * n;
  while (true) {
    const std::uint64_t used = all.size();
    if (used >= budget) break;
    const std::uint64_t gens = std::min<std::uint64_t>(std::uint64_t(s.generations_per_round), (budget - used) / per_generation);
    if (gens == 0) break;
    if (options.stop && options.stop->load()) {
      r.interrupted = true;
      break;
    }
    if (prior_seconds + elapsed() >= seconds_budget) {
      r.budget_time = true;
      break;
    }
    ++round;
    const std::vector<pagmo::population> before = pops;
    const std::vector<std::uint64_t> counted = counters;
    const bool halted = on_every_island(n, threads, [&](std::size_t k) {
      rounds[k] = round;
      const pagmo::algorithm a = make_algorithm(alg, unsigned(gens), seed32(s.seed, std::uint64_t(islands[k]), round),
                                                s.population, p.dimension(), s.objectives.size(), &p, &memory[k]);
      pops[k] = a.evolve(pops[k]);
    });
    if (halted) {
      // The round is abandoned as a whole, so that the checkpoint stays that of the last round.
      pops = before;
      counters = counted;
      for (auto& l : logs) l.clear();
      --round;
      if (options.stop && options.stop->load()) r.interrupted = true;
      else r.budget_time = true;
      break;
    }
    for (auto& l : logs) {
      all.insert(all.end(), l.begin(), l.end());
      l.clear();
    }
    // Migration in a ring: the best tenth of island k replaces the worst tenth of island k + 1.
    if (n > 1) {
      const std::size_t q = std::max<std::size_t>(1, std::size_t(s.population) / 10);
      std::vector<std::vector<std::pair<pagmo::vector_double, pagmo::vector_double>>> emigrants(n);
      for (std::size_t k = 0; k < n; ++k) {
        const auto& f = pops[k].get_f();
        const std::vector<pagmo::pop_size_t> order = best_first(f);
        for (std::size_t i = 0; i < q && i < order.size(); ++i) {
          emigrants[k].emplace_back(pops[k].get_x()[order[i]], f[order[i]]);
        }
      }
      for (std::size_t k = 0; k < n; ++k) {
        auto& dst = pops[(k + 1) % n];
        const std::vector<pagmo::pop_size_t> order = best_first(dst.get_f());
        for (std::size_t i = 0; i < emigrants[k].size() && i < order.size(); ++i) {
          dst.set_xf(order[order.size() - 1 - i], emigrants[k][i].first, emigrants[k][i].second);
        }
      }
    }
    // The checkpoint holds every candidate so far, so writing it after every round made a long run
    // quadratic (docs/reliability.md). It is written when at least kCheckpointSeconds and ten times
    // its own last writing time have passed since the last one: checkpoints take at most about a
    // tenth of the run (linear in it); an interrupted or finished run always writes its last round.
    if (elapsed() - checkpoint_at >= std::max(kCheckpointSeconds, 10.0 * checkpoint_cost)) write_checkpoint();
    if (options.progress) options.progress(all.size(), budget, prior_seconds + elapsed(), front_size());
  }
  if (round == 0 || r.interrupted || checkpoint_round != round) write_checkpoint();
  r.rounds = round;
  r.seconds = prior_seconds + elapsed();
  OptimizeResult out = finish(p, cache, design, std::move(all), options, r, options.shards == 1, seconds_budget - r.seconds);
  out.files.push_back(checkpoint);
  return out;
}

OptimizeResult merge_optimize_shards(const Design& design, const OptimizeOptions& options, std::uint64_t shards) {
  const OptimizeProblem p(design);
  std::vector<OptimizeCandidate> all;
  OptimizeResult r;
  r.algorithm = p.settings().resolved_algorithm();
  for (std::uint64_t k = 0; k < shards; ++k) {
    const auto path = options.out_dir / ("front" + shard_suffix(k, shards) + ".json");
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) {
      throw InputError(path.string() + ": shard " + std::to_string(k) + " of " + std::to_string(shards) + " is missing");
    }
    const Json j = read_optimize_file(path, "shard file");
    if (j.value("format", "") != kShardFormat || j.value("design_hash", "") != design_hash(p)) {
      throw InputError(path.string() + ": a shard of another design or other optimize: settings");
    }
    // Identity and sizes before use (docs/reliability.md): the file must say it is shard k of
    // `shards`, finished, with as many candidates as it holds.
    try {
      const std::uint64_t says = j.at("shard").get<std::uint64_t>(), of = j.at("shards").get<std::uint64_t>();
      if (says != k || of != shards) {
        throw InputError(path.string() + ": holds shard " + std::to_string(says) + " of " + std::to_string(of) +
                         ", not shard " + std::to_string(k) + " of " + std::to_string(shards));
      }
      if (j.at("interrupted").get<bool>()) {
        throw InputError(path.string() + ": shard " + std::to_string(k) + " of " + std::to_string(shards) +
                         " was interrupted: finish it first (resume shard " + std::to_string(k) + "/" +
                             std::to_string(shards) + "), then merge",
                         Remedy::resume_shard);
      }
      const Json& cs = j.at("candidates");
      if (j.contains("candidate_count") && j.at("candidate_count").get<std::uint64_t>() != cs.size()) {
        throw InputError(path.string() + ": says " + std::to_string(j.at("candidate_count").get<std::uint64_t>()) +
                         " candidates but holds " + std::to_string(cs.size()));
      }
      for (const Json& c : cs) {
        OptimizeCandidate cand = candidate_from(c);
        if (cand.x.size() != p.dimension() || cand.figures.size() != optimize_figures().size()) {
          throw InputError(path.string() + ": a candidate with " + std::to_string(cand.x.size()) + " values and " +
                           std::to_string(cand.figures.size()) + " figures (the design has " + std::to_string(p.dimension()) +
                           " variables and " + std::to_string(optimize_figures().size()) + " figures)");
        }
        all.push_back(std::move(cand));
      }
      r.seconds = std::max(r.seconds, j.at("seconds").get<double>());
      r.rounds = std::max<std::uint64_t>(r.rounds, j.at("rounds").get<std::uint64_t>());
    } catch (const InputError&) {
      throw;
    } catch (const std::exception& e) {
      throw InputError(path.string() + ": a damaged shard file (" + e.what() + ")");
    }
  }
  OptimizeOptions whole = options;
  whole.shard = 0;
  whole.shards = 1;
  EvaluationCache cache(p);
  for (const auto& c : all) cache.insert(c);
  return finish(p, cache, design, std::move(all), whole, r, true, options.seconds > 0.0 ? options.seconds : p.settings().seconds);
}

Json OptimizeResult::to_json(const OptimizeProblem& p) const {
  const auto& s = p.settings();
  Json j;
  j["algorithm"] = algorithm;
  j["islands"] = s.islands;
  j["population"] = s.population;
  j["seed"] = s.seed;
  j["evaluations"] = evaluations;
  j["distinct_evaluations"] = distinct;
  j["cache_hits"] = cache_hits;
  j["rounds"] = rounds;
  j["seconds"] = seconds;
  j["interrupted"] = interrupted;
  j["stopped_by_time"] = budget_time;
  j["stations"] = p.stations();
  j["stages"] = stages.to_json();
  j["variables"] = Json::array();
  for (const auto& v : s.variables) {
    j["variables"].push_back(Json{{"name", v.name}, {"keys", v.keys}, {"lo", v.lo}, {"hi", v.hi}, {"step", v.step}});
  }
  j["objectives"] = Json::array();
  for (const auto& o : s.objectives) j["objectives"].push_back(Json{{"figure", o.figure}, {"goal", o.maximise ? "max" : "min"}});
  j["constraints"] = Json::array();
  for (const auto& c : s.constraints) j["constraints"].push_back(c.text());
  auto point = [&](const OptimizeCandidate& c) {
    Json values = Json::object(), figures = Json::object();
    for (std::size_t d = 0; d < s.variables.size() && d < c.x.size(); ++d) values[s.variables[d].name] = c.x[d];
    for (std::size_t i = 0; i < optimize_figures().size() && i < c.figures.size(); ++i) {
      if (std::isfinite(c.figures[i])) figures[std::string(optimize_figures()[i].name)] = c.figures[i];
    }
    return Json{{"values", values}, {"figures", figures}, {"verdict", to_string(c.verdict)}, {"status", c.status},
                {"island", c.island}, {"round", c.round}, {"evaluation", c.evaluation}};
  };
  j["front"] = Json::array();
  for (const auto& c : front) j["front"].push_back(point(c));
  j["hypervolume"] = Json::array();
  for (const auto& [e, h] : hypervolume) j["hypervolume"].push_back(Json{{"evaluations", e}, {"value", h}});
  j["ideal"] = Json::array();
  j["nadir"] = Json::array();
  for (double v : ideal) j["ideal"].push_back(opt(v));
  for (double v : nadir) j["nadir"].push_back(opt(v));
  j["reference"] = point(reference);
  j["chosen"] = chosen ? point(*chosen) : Json(nullptr);
  j["polished"] = polished ? point(*polished) : Json(nullptr);
  j["polish_evaluations"] = polish_evaluations;
  j["atlases"] = atlases;
  return j;
}

}  // namespace fivebar
