// SPDX-License-Identifier: LGPL-2.1-or-later
// FemBspTet core: the out-of-core mode, a solid meshed in pieces (out_of_core.h).
#include "bsptet/pieces/out_of_core.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <condition_variable>
#include <exception>
#include <future>
#include <memory>
#include <mutex>
#include <thread>

#include "bsptet/numerics/errors.h"
#include "bsptet/mesh/mesh_check.h"
#include "bsptet/input/self_intersection.h"
#include "bsptet/pieces/solid_cut.h"
#include "bsptet/input/surface_check.h"

namespace bsptet {

SurfaceMesh piece_surface(const std::vector<double>& points, const std::vector<Index>& tri, std::vector<Index>& globals) {
  globals.assign(tri.begin(), tri.end());
  std::sort(globals.begin(), globals.end());
  globals.erase(std::unique(globals.begin(), globals.end()), globals.end());
  SurfaceMesh s;
  s.xyz.reserve(3 * globals.size());
  for (Index g : globals) s.xyz.insert(s.xyz.end(), &points[3 * static_cast<std::size_t>(g)], &points[3 * static_cast<std::size_t>(g) + 3]);
  s.tri.resize(tri.size());
  for (std::size_t i = 0; i < tri.size(); ++i)
    s.tri[i] = static_cast<Index>(std::lower_bound(globals.begin(), globals.end(), tri[i]) - globals.begin());
  return s;
}

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

constexpr std::int64_t kBaseBytes = 32LL << 20;
constexpr std::int64_t kBytesPerTriangle = 2LL << 10;
constexpr int kRepairRounds = 8;
constexpr double kCapEdgeWeight = 3.0;
constexpr std::int64_t kMaxRepairPairs = 100000;

// Empty when check_surface accepts the piece as it is, but for its self-intersection search,
// else its message. That search is cap_crossings': a piece's triangles other than its new caps'
// are its parent's, which do not cross each other (the parent was checked), so the pairs to look
// at are those with a cap triangle, and both of those meet the caps' box.
std::string surface_problem(const std::vector<double>& points, const std::vector<Index>& tri) {
  std::vector<Index> globals;
  SurfaceCheckOptions options;
  options.self_intersections = false;
  try {
    check_surface(piece_surface(points, tri, globals), options);
  } catch (const InputError& e) {
    return e.what();
  }
  return {};
}

// The surface triangles of a piece (source >= 0) that a cap triangle of it (source < 0) crosses,
// by the exact search of self_intersection.h on the caps and the triangles whose boxes meet the
// caps' box; `caps_cross` is set when two cap triangles cross each other (or the search was cut
// short). Nothing found and nothing set: no triangle pair with a cap triangle intersects.
std::vector<Index> cap_crossings(const std::vector<double>& points, const std::vector<Index>& piece,
                                 const std::vector<Index>& source, bool& caps_cross) {
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (std::size_t t = 0; t < source.size(); ++t)
    if (source[t] < 0)
      for (int k = 0; k < 3; ++k)
        for (int a = 0; a < 3; ++a) {
          const double x = points[3 * static_cast<std::size_t>(piece[3 * t + k]) + a];
          lo[a] = std::min(lo[a], x), hi[a] = std::max(hi[a], x);
        }
  std::vector<Index> near, from;  // the triangles near the caps; near's triangle -> piece triangle
  for (std::size_t t = 0; t < source.size(); ++t) {
    bool meets = true;
    for (int a = 0; a < 3 && meets; ++a) {
      double l = HUGE_VAL, h = -HUGE_VAL;
      for (int k = 0; k < 3; ++k) {
        const double x = points[3 * static_cast<std::size_t>(piece[3 * t + k]) + a];
        l = std::min(l, x), h = std::max(h, x);
      }
      meets = l <= hi[a] && h >= lo[a];
    }
    if (!meets) continue;
    near.insert(near.end(), &piece[3 * t], &piece[3 * t + 3]);
    from.push_back(static_cast<Index>(t));
  }
  std::vector<Index> globals;
  std::vector<Index> crossed;
  bool complete = true;
  for (const auto& pair : find_self_intersections(piece_surface(points, near, globals), kMaxRepairPairs, &complete)) {
    const Index a = source[from[pair[0]]], b = source[from[pair[1]]];
    if ((a < 0) != (b < 0)) crossed.push_back(a < 0 ? b : a);
    caps_cross = caps_cross || (a < 0 && b < 0);
  }
  caps_cross = caps_cross || !complete;
  return crossed;
}

// Runs f and g, on two threads when `parallel` (neither may touch what the other writes).
template <class F, class G>
void both(bool parallel, F&& f, G&& g) {
  if (!parallel) {
    f();
    g();
    return;
  }
  auto later = std::async(std::launch::async, std::forward<G>(g));
  f();
  later.get();
}

// Cuts the piece `tri` in two (below, above) by the first cut that solid_cut makes and that
// check_surface accepts on both sides (candidates below; points from first_cap_point on are
// earlier caps'). Where a cap crosses a surface
// triangle, the triangles around that triangle's vertices are moved to the other side and the
// cut made again (at most kRepairRounds times). False when no cut works. With `parallel`, the
// two sides are searched and checked on two threads.
bool cut_piece(std::vector<double>& points, Index first_cap_point, const std::vector<Index>& tri,
               std::vector<Index>& below, std::vector<Index>& above, PieceStats& st,
               const std::function<void(const std::string&)>& log, bool parallel) {
  const std::size_t n = tri.size() / 3;
  // Candidate cuts: across each axis at the quantiles 0.3, 0.35, ..., 0.7 of the triangles'
  // corner sums.
  const SolidTopology topology(tri);
  const std::vector<Index>& across = topology.across;
  // Ordered by the length of the edges between the two sides before smoothing, those on an
  // earlier cap counted kCapEdgeWeight times: a plane that grazes the surface or crosses long
  // thin triangles (a CAD strip along the axis) makes a long zigzag loop whose cap has needles
  // and crosses the surface; a loop that runs onto a flat cap, along its rim, folds in projection
  // more often than one on the surface (but weighing caps more than that would favour parallel
  // slabs, whose caps become a large part of thin pieces).
  struct Candidate {
    double weight;
    int axis;
    double threshold;
  };
  std::vector<char> touches_cap(n);
  for (std::size_t t = 0; t < n; ++t)
    for (int k = 0; k < 3; ++k) touches_cap[t] = touches_cap[t] || tri[3 * t + k] >= first_cap_point;
  std::vector<double> edge_length(across.size());
  for (std::size_t i = 0; i < across.size(); ++i) {
    const std::size_t a = 3 * static_cast<std::size_t>(tri[i]), b = 3 * static_cast<std::size_t>(tri[i / 3 * 3 + (i + 1) % 3]);
    edge_length[i] = std::hypot(points[a] - points[b], points[a + 1] - points[b + 1], points[a + 2] - points[b + 2]);
  }
  std::vector<Candidate> candidates;
  std::vector<double> sums(n), sorted(n);
  for (int axis = 0; axis < 3; ++axis) {
    for (std::size_t t = 0; t < n; ++t) sums[t] = corner_sum(points, &tri[3 * t], axis);
    // The quantiles are order statistics: successive selections, each in what the last left above.
    sorted = sums;
    const double smallest = *std::min_element(sorted.begin(), sorted.end());
    const std::size_t first = candidates.size();
    std::size_t from = 0;
    for (int q = 6; q <= 14; ++q) {
      const std::size_t rank = std::min(n - 1, std::max<std::size_t>(1, n * static_cast<std::size_t>(q) / 20));
      std::nth_element(sorted.begin() + static_cast<std::ptrdiff_t>(from), sorted.begin() + static_cast<std::ptrdiff_t>(rank), sorted.end());
      from = rank;
      const double threshold = sorted[rank];
      if (threshold == smallest) continue;
      bool seen = false;
      for (const auto& c : candidates) seen = seen || (c.axis == axis && c.threshold == threshold);
      if (!seen) candidates.push_back({0, axis, threshold});
    }
    // One pass over the edges for this axis's thresholds (increasing): an edge is between the two
    // sides of threshold T when its triangles' sums a, b have min(a, b) < T <= max(a, b).
    for (std::size_t i = 0; i < across.size(); ++i) {
      if (across[i] < 0) continue;
      const std::size_t t = i / 3, u = static_cast<std::size_t>(across[i]);
      const double lo = std::min(sums[t], sums[u]), hi = std::max(sums[t], sums[u]);
      if (!(lo < hi)) continue;
      const double w = edge_length[i] * (touches_cap[t] || touches_cap[u] ? kCapEdgeWeight : 1);
      for (std::size_t c = first; c < candidates.size(); ++c)
        if (lo < candidates[c].threshold && candidates[c].threshold <= hi) candidates[c].weight += w;
    }
  }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& a, const Candidate& b) { return a.weight < b.weight; });
  for (const Candidate& candidate : candidates) {
    const int axis = candidate.axis;
    const double threshold = candidate.threshold;
    const std::string where = "cut of a piece of " + std::to_string(n) + " triangles across " + "xyz"[axis] +
                              " at corner sum " + std::to_string(threshold);
    std::vector<std::pair<Index, char>> forced;
    std::string why;
    for (int round = 0; round <= kRepairRounds && why.empty(); ++round) {
      SolidCut cut = cut_solid(points, tri, axis, threshold, forced, &topology);
      if (!cut.ok) {
        why = cut.reason;
        break;
      }
      const std::size_t old_size = points.size();
      points.insert(points.end(), cut.new_points.begin(), cut.new_points.end());  // dropped if refused
      // Repair where a cap crosses a surface triangle (found near the caps only), then check both
      // pieces' topology and orientation whole (surface_problem).
      std::size_t crossings = 0;
      std::vector<Index> crossed[2];  // [0] above, [1] below
      bool caps_cross[2] = {false, false};
      both(parallel, [&] { crossed[1] = cap_crossings(points, cut.below, cut.below_source, caps_cross[1]); },
           [&] { crossed[0] = cap_crossings(points, cut.above, cut.above_source, caps_cross[0]); });
      for (int side = 1; side >= 0; --side)
        for (Index t : crossed[side]) {
          ++crossings;
          for (int k = 0; k < 3; ++k) forced.emplace_back(tri[3 * static_cast<std::size_t>(t) + k], static_cast<char>(!side));
        }
      if (crossings > 0) {
        points.resize(old_size);
        if (round == kRepairRounds) why = std::to_string(crossings) + " surface triangles still cross its caps after " +
                                          std::to_string(kRepairRounds) + " repairs";
        continue;
      }
      if (caps_cross[0] || caps_cross[1]) {
        points.resize(old_size);
        why = "its cap triangles cross each other";
        break;
      }
      std::string why_above;
      both(parallel, [&] { why = surface_problem(points, cut.below); },
           [&] { why_above = surface_problem(points, cut.above); });
      if (why.empty()) why = why_above;
      if (!why.empty()) {
        points.resize(old_size);
        break;
      }
      ++st.cuts;
      st.cap_triangles += cut.cap_triangles;
      st.cap_points += cut.cap_points;
      if (log)
        log(where + ": " + std::to_string(cut.below.size() / 3) + " + " + std::to_string(cut.above.size() / 3) +
            " triangles, " + std::to_string(cut.loops) + " loops, " + std::to_string(cut.cap_triangles) +
            " cap triangles, " + std::to_string(cut.cap_points) + " cap points" +
            (round ? ", after " + std::to_string(round) + " repairs" : std::string()));
      below = std::move(cut.below);
      above = std::move(cut.above);
      return true;
    }
    ++st.cuts_refused;
    st.refused.push_back(where + ": " + why);
    if (log) log(where + " refused: " + why);
  }
  return false;
}

// Files removed when the run ends, however it ends (removing a renamed one does nothing).
struct Scratch {
  std::vector<std::string> paths;
  ~Scratch() {
    for (const auto& p : paths) std::remove(p.c_str());
  }
};

struct FileCloser {
  void operator()(std::FILE* f) const {
    if (f) std::fclose(f);
  }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

File open_file(const std::string& path, const char* mode) {
  File f(std::fopen(path.c_str(), mode));
  if (!f) throw InputError(ErrorCode::kBadArgument, "write", -1, path + ": cannot open for writing");
  return f;
}

void finish(File& f, const std::string& path) {
  const bool bad = std::ferror(f.get()) != 0;
  if (std::fclose(f.release()) != 0 || bad)
    throw InputError(ErrorCode::kBadArgument, "write", -1, path + ": write failed (disk full?)");
}

}  // namespace

std::int64_t estimated_core_peak_bytes(std::int64_t triangles) { return kBaseBytes + kBytesPerTriangle * triangles; }

std::int64_t piece_triangles_for_budget(std::int64_t budget_bytes) {
  return std::max<std::int64_t>(1000, (budget_bytes - kBaseBytes) / kBytesPerTriangle);
}

std::int64_t piece_triangles_for_workers(std::int64_t triangles, int workers) {
  if (workers <= 1) return 0;
  return (5 * triangles + 4 * workers - 1) / (4 * workers);
}

SolidPieces cut_into_pieces(const SurfaceMesh& surface, const MeshOptions& options, const PieceOptions& po,
                            PieceStats* stats) {
  PieceStats local_stats;
  PieceStats& st = stats ? *stats : local_stats;
  // Depth first, below before above: deterministic.
  const auto t0 = Clock::now();
  SolidPieces solid;
  solid.xyz = surface.xyz;
  solid.input_points = surface.num_points();
  std::vector<std::vector<Index>> todo{surface.tri};
  while (!todo.empty()) {
    std::vector<Index> tri = std::move(todo.back());
    todo.pop_back();
    const std::int64_t n = static_cast<std::int64_t>(tri.size() / 3);
    if (po.max_piece_triangles <= 0 || n <= po.max_piece_triangles || n <= po.min_piece_triangles) {
      solid.pieces.push_back(std::move(tri));
      continue;
    }
    if (options.cancelled && options.cancelled()) throw MeshingError(ErrorCode::kCancelled, "pieces", -1, "cancelled");
    if (options.progress) options.progress("cutting into pieces", 0);
    std::vector<Index> below, above;
    const std::size_t refused_before = st.refused.size();
    if (!cut_piece(solid.xyz, solid.input_points, tri, below, above, st, po.log, po.workers > 1)) {
      std::string reasons;
      for (std::size_t i = std::max(refused_before, st.refused.size() >= 3 ? st.refused.size() - 3 : 0); i < st.refused.size(); ++i)
        reasons += "\n  " + st.refused[i];
      st.uncut.push_back("a piece of " + std::to_string(n) + " triangles could not be cut (every cut tried was refused; the last ones:" +
                         reasons + "\n): it is meshed whole");
      if (po.log) po.log(st.uncut.back());
      solid.pieces.push_back(std::move(tri));
      continue;
    }
    todo.push_back(std::move(above));
    todo.push_back(std::move(below));
  }
  st.pieces = static_cast<std::int64_t>(solid.pieces.size());
  for (const auto& p : solid.pieces) st.largest_piece_triangles = std::max<std::int64_t>(st.largest_piece_triangles, p.size() / 3);
  st.seconds_cutting = since(t0);
  return solid;
}

TetMesh mesh_piece(const SurfaceMesh& piece, const MeshOptions& options, bool check, const std::string& name,
                   MeshStats* stats) {
  TetMesh m = tetrahedralize(piece, options, stats);
  if (m.num_points() < piece.num_points() || !std::equal(piece.xyz.begin(), piece.xyz.end(), m.xyz.begin()))
    throw MeshingError(ErrorCode::kInternal, "pieces", -1, name + ": the core did not put the piece's input points first");
  if (check) {
    MeshCheckOptions co;
    co.compute_quality = false;
    co.max_messages = 3;
    const MeshCheckReport r = check_mesh(piece, m, co);
    if (!r.valid) {
      std::string msg = name + ": its mesh failed the exact check";
      for (const auto& s : r.messages) msg += "; " + s;
      throw MeshingError(ErrorCode::kInternal, "pieces", -1, msg);
    }
  }
  return m;
}

std::vector<Index> merged_point_ids(const SolidPieces& solid) {
  std::vector<Index> out_id(solid.xyz.size() / 3, -1);
  for (const auto& piece : solid.pieces)
    for (Index v : piece) out_id[v] = 0;
  for (std::size_t v = static_cast<std::size_t>(solid.input_points); v < out_id.size(); ++v) out_id[v] = 0;
  Index used = 0;
  for (Index& id : out_id)
    if (id == 0) id = used++;
  return out_id;
}

void tetrahedralize_in_pieces(const SurfaceMesh& surface, const MeshOptions& options, const PieceOptions& po,
                              const std::string& stem, PieceStats* stats) {
  if (options.allow_boundary_steiner)
    throw InputError(ErrorCode::kBadArgument, "pieces", -1,
                     "the out-of-core mode needs the default allow_boundary_steiner = false: its pieces must meet "
                     "in exactly their caps' triangles");
  if (po.workers < 1) throw InputError(ErrorCode::kBadArgument, "pieces", -1, "workers must be at least 1");
  PieceStats st;
  // 1. Cut until every piece is small enough.
  SolidPieces solid = cut_into_pieces(surface, options, po, &st);
  const std::size_t count = solid.pieces.size();

  // 2. Output numbering.
  const std::vector<Index> out_id = merged_point_ids(solid);
  Index used = 0;
  for (Index id : out_id) used = std::max(used, id + 1);

  // 3. Mesh the pieces, `workers` at a time, spooling their Steiner points and tets in piece
  // order as they become ready.
  Scratch scratch;
  const std::string steiner_path = stem + ".steiner.spool", tets_path = stem + ".tets.spool";
  scratch.paths = {steiner_path, tets_path, stem + ".node.part", stem + ".ele.part"};
  File steiner_spool = open_file(steiner_path, "wb"), tets_spool = open_file(tets_path, "wb");
  auto t0 = Clock::now();
  struct Done {
    bool ready = false;
    std::vector<Index> globals;
    TetMesh mesh;
    double seconds = 0;
    std::exception_ptr error;
  };
  std::vector<Done> done(count);
  std::mutex mutex;  // guards `done`, `next`, `stop` and the calls of the caller's callbacks
  std::condition_variable ready;
  std::size_t next = 0;
  bool stop = false;
  const bool serial = po.workers == 1 || count == 1;
  auto name_of = [&](std::size_t p) { return "piece " + std::to_string(p + 1) + "/" + std::to_string(count); };
  // Meshes the next piece; false when there is none left or the run stops.
  auto mesh_next = [&]() -> bool {
    std::size_t p;
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (stop || next == count) return false;
      p = next++;
    }
    {
      Done d;
      try {
        const auto tp = Clock::now();
        const SurfaceMesh local = piece_surface(solid.xyz, solid.pieces[p], d.globals);
        MeshOptions o = options;
        o.cancelled = [&] {
          std::lock_guard<std::mutex> lock(mutex);
          return stop || (options.cancelled && options.cancelled());
        };
        if (options.progress && serial)
          o.progress = [&](const std::string& stage, double f) { options.progress(name_of(p) + ": " + stage, f); };
        else
          o.progress = nullptr;
        d.mesh = mesh_piece(local, o, po.check_pieces, name_of(p));
        d.seconds = since(tp);
      } catch (...) {
        d.error = std::current_exception();
      }
      std::lock_guard<std::mutex> lock(mutex);
      if (d.error) stop = true;
      d.ready = true;
      done[p] = std::move(d);
      ready.notify_all();
    }
    return true;
  };
  std::vector<std::thread> threads;
  struct Joiner {
    std::vector<std::thread>& threads;
    std::mutex& mutex;
    bool& stop;
    ~Joiner() {
      {
        std::lock_guard<std::mutex> lock(mutex);
        stop = true;
      }
      for (auto& t : threads) t.join();
    }
  } joiner{threads, mutex, stop};
  if (!serial)
    for (int w = 0; w < std::min<int>(po.workers, static_cast<int>(count)); ++w)
      threads.emplace_back([&] {
        while (mesh_next()) {
        }
      });
  std::int64_t steiner = 0;
  for (std::size_t p = 0; p < count; ++p) {
    if (serial) {
      if (options.cancelled && options.cancelled()) throw MeshingError(ErrorCode::kCancelled, "pieces", -1, "cancelled");
      mesh_next();  // piece p
    }
    Done d;
    {
      std::unique_lock<std::mutex> lock(mutex);
      if (!serial && options.progress) {
        lock.unlock();
        options.progress("meshing " + std::to_string(count) + " pieces on " + std::to_string(threads.size()) + " threads",
                         static_cast<double>(p) / static_cast<double>(count));
        lock.lock();
      }
      ready.wait(lock, [&] { return done[p].ready; });
      d = std::move(done[p]);
      done[p] = Done{};
    }
    if (d.error) std::rethrow_exception(d.error);
    const TetMesh& m = d.mesh;
    const Index nloc = static_cast<Index>(d.globals.size());
    std::fwrite(m.xyz.data() + 3 * static_cast<std::size_t>(nloc), sizeof(double),
                m.xyz.size() - 3 * static_cast<std::size_t>(nloc), steiner_spool.get());
    std::vector<Index> tets(m.tet.size());
    for (std::size_t i = 0; i < m.tet.size(); ++i) {
      const Index v = m.tet[i];
      tets[i] = v < nloc ? out_id[d.globals[v]] : static_cast<Index>(used + steiner + (v - nloc));
    }
    std::fwrite(tets.data(), sizeof(Index), tets.size(), tets_spool.get());
    steiner += m.num_points() - nloc;
    st.tets += m.num_tets();
    if (po.log)
      po.log(name_of(p) + ": " + std::to_string(solid.pieces[p].size() / 3) + " triangles -> " +
             std::to_string(m.num_tets()) + " tets, " + std::to_string(m.num_points() - nloc) + " Steiner points, " +
             std::to_string(d.seconds) + " s" + (po.check_pieces ? ", checked: valid" : ""));
    solid.pieces[p] = {};
  }
  finish(steiner_spool, steiner_path);
  finish(tets_spool, tets_path);
  st.pieces_checked = po.check_pieces;
  st.steiner_points = steiner;
  st.points = used + steiner;
  st.seconds_meshing = since(t0);

  // 4. Stream the spools into stem.node / stem.ele (temporary names first).
  t0 = Clock::now();
  if (options.progress) options.progress("writing", 0);
  {
    File node = open_file(stem + ".node.part", "w");
    std::fprintf(node.get(), "%lld 3 0 0\n", static_cast<long long>(st.points));
    long long line = 0;
    for (std::size_t g = 0; g < out_id.size(); ++g)
      if (out_id[g] >= 0)
        std::fprintf(node.get(), "%lld %.17g %.17g %.17g\n", ++line, solid.xyz[3 * g], solid.xyz[3 * g + 1], solid.xyz[3 * g + 2]);
    File in = File(std::fopen(steiner_path.c_str(), "rb"));
    std::vector<double> buf(3 * 4096);
    for (std::size_t got; in && (got = std::fread(buf.data(), sizeof(double), buf.size(), in.get())) > 0;)
      for (std::size_t i = 0; i + 2 < got; i += 3)
        std::fprintf(node.get(), "%lld %.17g %.17g %.17g\n", ++line, buf[i], buf[i + 1], buf[i + 2]);
    if (line != st.points) throw MeshingError(ErrorCode::kInternal, "pieces", -1, "the Steiner spool is short");
    finish(node, stem + ".node.part");
  }
  {
    File ele = open_file(stem + ".ele.part", "w");
    std::fprintf(ele.get(), "%lld 4 0\n", static_cast<long long>(st.tets));
    File in = File(std::fopen(tets_path.c_str(), "rb"));
    std::vector<Index> buf(4 * 4096);
    long long line = 0;
    for (std::size_t got; in && (got = std::fread(buf.data(), sizeof(Index), buf.size(), in.get())) > 0;)
      for (std::size_t i = 0; i + 3 < got; i += 4)
        std::fprintf(ele.get(), "%lld %d %d %d %d\n", ++line, buf[i] + 1, buf[i + 1] + 1, buf[i + 2] + 1, buf[i + 3] + 1);
    if (line != st.tets) throw MeshingError(ErrorCode::kInternal, "pieces", -1, "the tet spool is short");
    finish(ele, stem + ".ele.part");
  }
  if (std::rename((stem + ".node.part").c_str(), (stem + ".node").c_str()) != 0 ||
      std::rename((stem + ".ele.part").c_str(), (stem + ".ele").c_str()) != 0)
    throw InputError(ErrorCode::kBadArgument, "write", -1, stem + ": cannot rename the finished .node/.ele into place");
  st.seconds_writing = since(t0);
  if (stats) *stats = std::move(st);
}

}  // namespace bsptet
