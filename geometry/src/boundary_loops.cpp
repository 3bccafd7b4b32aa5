#include "solo/geometry/boundary_loops.h"

#include <algorithm>
#include <cstdlib>
#include <utility>
#include <unordered_map>

namespace solo {
namespace {

// Twice the signed area of a polygon of pixel positions (shoelace); in the image's y-down frame a
// hole's orientation (the border loop's opposite) is negative.
double twiceSignedArea(const std::vector<OpenMesh::Vec2i>& polygon) {
  double twice = 0;
  for (std::size_t q = 0; q < polygon.size(); ++q) {
    const auto& p0 = polygon[q];
    const auto& p1 = polygon[(q + 1) % polygon.size()];
    twice += double(p0[0]) * p1[1] - double(p1[0]) * p0[1];
  }
  return twice;
}

// How a hole in DepthLoops::holes is to be closed: by its frame_paths entry (along the frame, or
// nothing to add for an inner hole), by the chord between its ends, along the sky line, or as
// the joined runs of several sheets (with its path_after entry).
enum class ClosedBy { Path, Chord, SkyLine, JoinedRuns, Backdrop };

// Appends a hole with its entry in every per-hole array of DepthLoops, which stay aligned.
void appendHole(DepthLoops& out, VertexLoop hole, ClosedBy by, std::vector<OpenMesh::Vec2i> path = {},
                std::vector<int> after = {}, bool frame_hole = true) {
  out.holes.push_back(std::move(hole));
  out.frame_paths.push_back(std::move(path));
  out.path_after.push_back(std::move(after));
  out.chord_closed.push_back(by == ClosedBy::Chord);
  out.sky_line_closed.push_back(by == ClosedBy::SkyLine);
  out.merged.push_back(by == ClosedBy::JoinedRuns || by == ClosedBy::Backdrop);
  out.backdrop.push_back(by == ClosedBy::Backdrop);
  out.frame_hole.push_back(frame_hole);
}

// The eight neighbours of a pixel, clockwise in the image (v down).
constexpr int kDu[8] = {1, 1, 0, -1, -1, -1, 0, 1};
constexpr int kDv[8] = {0, 1, 1, 1, 0, -1, -1, -1};

// The index in kDu/kDv of the step (du, dv), -1 for none.
int directionOf(int du, int dv) {
  for (int k = 0; k < 8; ++k)
    if (kDu[k] == du && kDv[k] == dv) return k;
  return -1;
}

using PixelPath = std::vector<OpenMesh::Vec2i>;
using PixelIndex = std::unordered_map<std::int64_t, std::size_t>;  // pixel key -> an index

// A depth mesh with the map it was made from: the pixel queries the classification makes.
struct DepthImage {
  const DepthMesh& m;
  const cv::Mat& had_depth;
  const cv::Mat& depth_m;
  int w, h;
  int perimeter;  // steps around the frame

  DepthImage(const DepthMesh& mesh, const cv::Mat& had, const cv::Mat& depth)
      : m(mesh), had_depth(had), depth_m(depth), w(mesh.width), h(mesh.height), perimeter(2 * (w - 1) + 2 * (h - 1)) {}

  OpenMesh::Vec2i pixelOf(OpenMesh::VertexHandle v) const { return m.mesh.property(m.properties.pixel, v); }
  // The pixels of a run's vertices, in order.
  PixelPath polygonOf(const VertexLoop& run) const {
    PixelPath polygon;
    for (const auto v : run) polygon.push_back(pixelOf(v));
    return polygon;
  }
  // The frame sides the pixel lies on (bits: 1 left, 2 right, 4 top, 8 bottom).
  int frameSides(const OpenMesh::Vec2i& p) const {
    return (p[0] == 0 ? 1 : 0) | (p[0] == w - 1 ? 2 : 0) | (p[1] == 0 ? 4 : 0) | (p[1] == h - 1 ? 8 : 0);
  }
  bool hasDepth(int u, int v) const { return u >= 0 && v >= 0 && u < w && v < h && had_depth.at<std::uint8_t>(v, u) != 0; }
  bool nextToNoDepth(const OpenMesh::Vec2i& p) const {
    for (int dv = -1; dv <= 1; ++dv)
      for (int du = -1; du <= 1; ++du) {
        const int u = p[0] + du, v = p[1] + dv;
        if (u >= 0 && v >= 0 && u < w && v < h && !had_depth.at<std::uint8_t>(v, u)) return true;
      }
    return false;
  }
  // Behind an occluder: a neighbouring pixel, not joined to this vertex by an edge, is nearer.
  bool behindOccluder(OpenMesh::VertexHandle vh) const {
    const OpenMesh::Vec2i p = pixelOf(vh);
    const double z = depth_m.at<float>(p[1], p[0]);
    for (int dv = -1; dv <= 1; ++dv)
      for (int du = -1; du <= 1; ++du) {
        const int u = p[0] + du, v = p[1] + dv;
        if ((du == 0 && dv == 0) || u < 0 || v < 0 || u >= w || v >= h || !had_depth.at<std::uint8_t>(v, u)) continue;
        if (depth_m.at<float>(v, u) >= 0.99 * z) continue;
        const int q = m.vertexAt(u, v);
        bool joined = false;
        if (q >= 0)
          for (const auto n : m.mesh.vv_range(vh)) joined = joined || n.idx() == q;
        if (!joined) return true;
      }
    return false;
  }
  // Whether the pixel's vertex (if it has a live one) lies itself behind an occluder.
  bool vertexBehindOccluder(const OpenMesh::Vec2i& p) const {
    const int q = m.vertexAt(p[0], p[1]);
    return q >= 0 && !m.mesh.status(OpenMesh::VertexHandle(q)).deleted() && behindOccluder(OpenMesh::VertexHandle(q));
  }
  std::int64_t key(const OpenMesh::Vec2i& p) const { return std::int64_t(p[1]) * w + p[0]; }
  // A frame pixel's position along the frame, clockwise from the top-left corner.
  int frameParameter(const OpenMesh::Vec2i& p) const {
    if (p[1] == 0) return p[0];
    if (p[0] == w - 1) return (w - 1) + p[1];
    if (p[1] == h - 1) return (w - 1) + (h - 1) + (w - 1 - p[0]);
    return 2 * (w - 1) + (h - 1) + (h - 1 - p[1]);
  }
  // The frame pixel at position t (taken modulo the perimeter).
  OpenMesh::Vec2i framePixel(int t) const {
    t = ((t % perimeter) + perimeter) % perimeter;
    if (t <= w - 1) return OpenMesh::Vec2i(t, 0);
    if (t <= (w - 1) + (h - 1)) return OpenMesh::Vec2i(w - 1, t - (w - 1));
    if (t <= 2 * (w - 1) + (h - 1)) return OpenMesh::Vec2i(w - 1 - (t - (w - 1) - (h - 1)), h - 1);
    return OpenMesh::Vec2i(0, h - 1 - (t - 2 * (w - 1) - (h - 1)));
  }
  // Whether direction `start` from pixel a begins an arc of background around it (the trace
  // of the contour has one start per such arc).
  bool startsBackgroundArc(const OpenMesh::Vec2i& a, int start) const {
    const int before = (start + 7) % 8;
    return !hasDepth(a[0] + kDu[start], a[1] + kDv[start]) && hasDepth(a[0] + kDu[before], a[1] + kDv[before]);
  }
  // One step along the outer contour of the pixels with depth: from `current`, whose background
  // neighbour lies in direction `back`, to the first neighbour with depth turning toward the
  // front (counter-clockwise in the image), so the depth lies on the left; `back` becomes the
  // last background neighbour as seen from `next` (-1 if not adjacent). False: no neighbour
  // has depth.
  bool contourStep(const OpenMesh::Vec2i& current, int& back, OpenMesh::Vec2i& next) const {
    int k = -1;
    for (int turn = 1; turn < 8 && k < 0; ++turn) {
      const int d = ((back - turn) % 8 + 8) % 8;
      if (hasDepth(current[0] + kDu[d], current[1] + kDv[d])) k = d;
    }
    if (k < 0) return false;
    const int behind = (k + 1) % 8;
    next = OpenMesh::Vec2i(current[0] + kDu[k], current[1] + kDv[k]);
    back = directionOf(current[0] + kDu[behind] - next[0], current[1] + kDv[behind] - next[1]);
    return true;
  }
  // Appends `next` to a path kept simple: a pixel reached again closes an excursion (a spike or
  // a lobe behind a one-pixel neck), which is dropped. `on_path` maps pixels to path indices.
  void appendSimple(PixelPath& path, PixelIndex& on_path, const OpenMesh::Vec2i& next) const {
    const auto seen = on_path.find(key(next));
    if (seen != on_path.end()) {
      for (std::size_t j = seen->second + 1; j < path.size(); ++j) on_path.erase(key(path[j]));
      path.resize(seen->second + 1);
    } else {
      on_path.emplace(key(next), path.size());
      path.push_back(next);
    }
  }
};

// A piece of a run behind an occluder becomes a frame hole; with both ends on the frame it is
// closed along the frame, going from its last vertex back to its first the way the border
// loop does not go: the loop runs clockwise in the image (positive signed area in (u, v)),
// so the closing path runs counter-clockwise, and the hole's polygon has a hole's
// orientation (negative area). A path over pixels without depth (sky) would close the hole
// over the sky: such pieces, and pieces ending on the sky line, keep the chord.
bool frameClosingPath(const DepthImage& image, const VertexLoop& run, PixelPath& path) {
  path.clear();
  const OpenMesh::Vec2i a = image.pixelOf(run.back()), b = image.pixelOf(run.front());
  if (image.w < 2 || image.h < 2 || image.frameSides(a) == 0 || image.frameSides(b) == 0) return false;
  const int ta = image.frameParameter(a), tb = image.frameParameter(b);
  const int steps = ((ta - tb) % image.perimeter + image.perimeter) % image.perimeter;  // counter-clockwise a -> b
  for (int s = 1; s < steps; ++s) {
    const OpenMesh::Vec2i p = image.framePixel(ta - s);
    if (!image.had_depth.at<std::uint8_t>(p[1], p[0])) return false;
    path.push_back(p);
  }
  PixelPath polygon = image.polygonOf(run);
  polygon.insert(polygon.end(), path.begin(), path.end());
  return twiceSignedArea(polygon) < 0;
}

// Closing along the sky line: from the run's last pixel the outer contour of the pixels with
// depth (the frame counting as their edge) is followed the way the border loop does not go,
// back to the run's first pixel. Next to a run that ends on the sky line beside a nearer
// occluder rising into the sky, that contour climbs the occluder's silhouette against the
// sky (and runs along the frame where the occluder meets it): the polygon covers what lies
// behind the occluder. Every pixel of the path must show a nearer surface than both ends of
// the run (the occluder) and no vertex lying itself behind an occluder: the contour must not
// go on over the far surface (another sheet of it, or the run's own sheet).
bool skyLinePath(const DepthImage& image, const VertexLoop& run, PixelPath& path) {
  path.clear();
  const OpenMesh::Vec2i a = image.pixelOf(run.back()), b = image.pixelOf(run.front());
  const double nearer_than_m =
      0.99 * std::min(image.depth_m.at<float>(a[1], a[0]), image.depth_m.at<float>(b[1], b[0]));
  PixelIndex on_path;  // pixel -> index in path
  std::unordered_map<std::int64_t, char> on_run;
  for (const auto v : run) on_run.emplace(image.key(image.pixelOf(v)), 1);
  const std::int64_t max_steps = 4 * std::int64_t(image.w) * image.h + 8;
  const auto trace = [&](int back) {
    path.clear();
    on_path.clear();
    OpenMesh::Vec2i current = a;
    for (std::int64_t step = 0; step < max_steps; ++step) {
      OpenMesh::Vec2i next;
      if (!image.contourStep(current, back, next)) return false;
      if (next == b) return true;
      if (next == a || on_run.count(image.key(next)) || back < 0) return false;
      if (!(image.depth_m.at<float>(next[1], next[0]) < nearer_than_m)) return false;
      if (image.vertexBehindOccluder(next)) return false;
      image.appendSimple(path, on_path, next);
      current = next;
    }
    return false;
  };
  // One try per arc of background around the run's end (the trace's first step differs).
  for (int start = 0; start < 8; ++start) {
    if (!image.startsBackgroundArc(a, start) || !trace(start)) continue;
    PixelPath polygon = image.polygonOf(run);
    polygon.insert(polygon.end(), path.begin(), path.end());
    if (twiceSignedArea(polygon) < 0) return true;
  }
  path.clear();
  return false;
}

// Runs of several sheets around one occluder (a far facade split by a tree crown or a car
// that touches the frame or the sky line): none closes alone, since the outline of the pixels
// with depth leads from its end onto the next sheet. Followed the same way as the sky-line
// path (counter-clockwise, over nearer pixels only), it may reach the first vertex of
// another such run; that run is taken in and the outline followed on from its last vertex,
// until it comes back to the first run's first vertex. The runs (known depth) and the paths
// between them (new vertices, depth extended) are one hole: the occluder's image behind it.
// Each path pixel must be nearer than 0.99 x both runs' ends it joins, and no vertex behind
// an occluder; the polygon must be simple with a hole's orientation. Runs left over keep
// the chord (or are unclosable).
// As a backdrop (`backdrop`): the same trace with no depth condition, for the runs that no
// closing path over nearer pixels reaches; a chain may be one run.
struct RunChainer {
  static constexpr std::size_t kMaxRunsPerHole = 16;

  const DepthImage& image;
  std::vector<VertexLoop>& runs;  // the runs closed are cleared
  bool backdrop;
  PixelIndex first_at, vertex_run;  // pixel -> run: of each run's first vertex, of every vertex
  std::vector<std::uint8_t> used;   // per run: closed in a hole
  std::int64_t max_steps;

  RunChainer(const DepthImage& image_in, std::vector<VertexLoop>& runs_in, bool backdrop_in)
      : image(image_in), runs(runs_in), backdrop(backdrop_in), used(runs_in.size(), 0),
        max_steps(4 * std::int64_t(image_in.w) * image_in.h + 8) {
    for (std::size_t r = 0; r < runs.size(); ++r) {
      if (runs[r].empty()) continue;  // closed already, or left out
      first_at.emplace(image.key(image.pixelOf(runs[r].front())), r);
      for (const auto v : runs[r]) vertex_run.emplace(image.key(image.pixelOf(v)), r);
    }
  }

  // A backdrop's trace takes a run's first vertex beside the pixel it reached: the runs'
  // ends need not lie on the outline itself (one pixel inside, by a thin far structure).
  std::ptrdiff_t firstBeside(const OpenMesh::Vec2i& p, bool at_start, std::size_t from, std::size_t closing,
                             const std::vector<std::uint8_t>& in_chain) const {
    for (int dv = -1; dv <= 1; ++dv)
      for (int du = -1; du <= 1; ++du) {
        // Off the image a pixel's key would name a pixel on the opposite side.
        if (p[0] + du < 0 || p[0] + du >= image.w || p[1] + dv < 0 || p[1] + dv >= image.h) continue;
        const auto found = first_at.find(image.key(OpenMesh::Vec2i(p[0] + du, p[1] + dv)));
        if (found == first_at.end()) continue;
        const std::size_t target = found->second;
        // The run's own start closes a chain of one run, but not at once (no region).
        if (target == from && (at_start || target != closing)) continue;
        if (target != closing && (used[target] || in_chain[target])) continue;
        return static_cast<std::ptrdiff_t>(target);
      }
    return -1;
  }

  // The outline from the last vertex of run `from`, its first step toward background direction
  // `start`: the first vertex of an unused run it reaches (returned, `path` leading there), or -1.
  std::ptrdiff_t walkOutline(std::size_t from, std::size_t closing, const std::vector<std::uint8_t>& in_chain,
                             int start, PixelPath& path) const {
    const OpenMesh::Vec2i a = image.pixelOf(runs[from].back());
    const double start_limit_m = 0.99 * image.depth_m.at<float>(a[1], a[0]);
    PixelIndex on_path;
    path.clear();
    double farthest_m = 0;
    OpenMesh::Vec2i current = a;
    int back = start;
    for (std::int64_t step = 0; step < max_steps; ++step) {
      OpenMesh::Vec2i next;
      if (!image.contourStep(current, back, next)) return -1;
      const auto on_run = vertex_run.find(image.key(next));
      if (backdrop && on_run == vertex_run.end()) {
        const std::ptrdiff_t beside = firstBeside(next, false, from, closing, in_chain);
        if (beside >= 0) {
          image.appendSimple(path, on_path, next);
          return beside;
        }
      }
      if (on_run != vertex_run.end()) {
        const auto first = first_at.find(image.key(next));
        if (first == first_at.end()) return -1;  // inside a run: not its start
        const std::size_t target = first->second;
        if (target != closing && (used[target] || in_chain[target])) return -1;
        if (!backdrop && !(farthest_m < 0.99 * image.depth_m.at<float>(next[1], next[0]))) return -1;
        return static_cast<std::ptrdiff_t>(target);
      }
      if (next == a || back < 0) return -1;
      const double z = image.depth_m.at<float>(next[1], next[0]);
      if (!backdrop) {
        if (!(z < start_limit_m)) return -1;
        if (image.vertexBehindOccluder(next)) return -1;
      }
      image.appendSimple(path, on_path, next);
      farthest_m = std::max(farthest_m, z);
      current = next;
    }
    return -1;
  }

  // From the last vertex of run `from`: the path to the first vertex of an unused run
  // (returned; `in_chain` excluded except `closing`, the chain's first run), or -1.
  std::ptrdiff_t trace(std::size_t from, std::size_t closing, const std::vector<std::uint8_t>& in_chain,
                       PixelPath& path) const {
    const OpenMesh::Vec2i a = image.pixelOf(runs[from].back());
    if (backdrop) {
      path.clear();
      const std::ptrdiff_t at_once = firstBeside(a, true, from, closing, in_chain);
      if (at_once >= 0) return at_once;
    }
    for (int start = 0; start < 8; ++start) {
      if (!image.startsBackgroundArc(a, start)) continue;
      const std::ptrdiff_t target = walkOutline(from, closing, in_chain, start, path);
      if (target >= 0) return target;
    }
    path.clear();
    return -1;
  }

  // Follows the outline from run r0 from run to run: whether it came back to r0, with the runs
  // taken in (`chain`, r0 first) and the path after each.
  bool chainFrom(std::size_t r0, std::vector<std::uint8_t>& in_chain, std::vector<std::size_t>& chain,
                 std::vector<PixelPath>& paths, std::vector<std::size_t>* dead_ends) const {
    chain = {r0};
    in_chain[r0] = 1;
    bool closed = false;
    while (chain.size() < kMaxRunsPerHole) {
      PixelPath path;
      const std::ptrdiff_t target = trace(chain.back(), r0, in_chain, path);
      if (target < 0) {
        if (dead_ends) dead_ends->push_back(chain.back());
        break;
      }
      paths.push_back(std::move(path));
      if (static_cast<std::size_t>(target) == r0) {
        closed = true;
        break;
      }
      chain.push_back(static_cast<std::size_t>(target));
      in_chain[chain.back()] = 1;
    }
    for (const std::size_t r : chain) in_chain[r] = 0;
    return closed;
  }

  // The chain's runs and paths as one hole, if they make one simple polygon with a hole's
  // orientation (every pixel once, negative area): appended to `out`, its runs marked used.
  void addChainHole(const std::vector<std::size_t>& chain, const std::vector<PixelPath>& paths, DepthLoops& out) {
    VertexLoop hole;
    PixelPath hole_path, polygon;
    std::vector<int> after;
    for (std::size_t j = 0; j < chain.size(); ++j) {
      for (const auto v : runs[chain[j]]) {
        hole.push_back(v);
        polygon.push_back(image.pixelOf(v));
      }
      for (const auto& p : paths[j]) {
        hole_path.push_back(p);
        after.push_back(static_cast<int>(hole.size()) - 1);
        polygon.push_back(p);
      }
    }
    std::unordered_map<std::int64_t, char> once;
    bool simple = true;
    for (const auto& p : polygon) simple = simple && once.emplace(image.key(p), 1).second;
    if (!simple || !(twiceSignedArea(polygon) < 0)) return;
    for (const std::size_t r : chain) used[r] = 1;
    appendHole(out, std::move(hole), backdrop ? ClosedBy::Backdrop : ClosedBy::JoinedRuns, std::move(hole_path),
               std::move(after));
    ++out.frame_holes;
    ++(backdrop ? out.frame_holes_backdrop : out.frame_holes_merged);
    (backdrop ? out.frame_hole_runs_backdrop : out.frame_hole_runs_merged) += static_cast<std::int64_t>(chain.size());
  }

  // Every chain that closes into a hole, into `out`; the runs it took are cleared. The runs
  // whose trace found no run's start are listed in `dead_ends` (if given).
  void closeChains(DepthLoops& out, std::vector<std::size_t>* dead_ends) {
    std::vector<std::uint8_t> in_chain(runs.size(), 0);
    for (std::size_t r0 = 0; r0 < runs.size(); ++r0) {
      if (used[r0] || runs[r0].empty()) continue;
      std::vector<std::size_t> chain;
      std::vector<PixelPath> paths;
      const bool closed = chainFrom(r0, in_chain, chain, paths, dead_ends);
      if (!closed || (chain.size() < 2 && !backdrop)) continue;
      addChainHole(chain, paths, out);
    }
    for (std::size_t r = 0; r < runs.size(); ++r)
      if (used[r]) runs[r].clear();
  }
};

// How many times a piece of a run may be cut again at its own chord.
constexpr int kMaxChordCutDepth = 4;

// The frame holes of a depth mesh's border loops: which runs behind an occluder become holes,
// and how each is closed.
struct FrameHoleCloser {
  const DepthImage& image;
  BackdropMode backdrops;
  DepthLoops& out;
  std::vector<VertexLoop> pending;    // frame-hole runs with no closing path of their own
  std::vector<VertexLoop> enclosing;  // frame-hole runs for backdrops

  // A run mostly behind an occluder: closed along the frame, else along the sky line, else
  // left pending (or kept for a backdrop).
  void addFrameHole(const VertexLoop& run) {
    std::size_t behind = 0;
    for (std::size_t e = 1; e + 1 < run.size(); ++e) behind += image.behindOccluder(run[e]);
    if (2 * behind < run.size() - 2) return;
    if (backdrops == BackdropMode::EveryFrameHole) {
      enclosing.push_back(run);
      return;
    }
    PixelPath path;
    const bool closed_along_frame = frameClosingPath(image, run, path);  // (a path may be empty: neighbouring ends)
    if (!closed_along_frame) {
      // Next along the sky line, over the occluder's outline: before the chord, which cuts
      // the occluder's part above the run's ends off (and sees no sky behind it).
      if (skyLinePath(image, run, path)) {
        appendHole(out, run, ClosedBy::SkyLine, std::move(path));
        ++out.frame_holes;
        ++out.frame_holes_sky_line;
        return;
      }
      // Perhaps it closes together with the runs of other sheets around the same occluder
      // (decided once every run is known), else by its chord.
      pending.push_back(run);
      return;
    }
    appendHole(out, run, ClosedBy::Path, std::move(path));
    ++out.frame_holes;
  }

  void addChordOrUnclosable(const VertexLoop& run) {
    // Closed by its chord, the run turning the loop's way (positive area) encloses its own
    // sheet: the sheet's faces lie on the polygon's inner side all along the run, so every
    // patch over that polygon lies on the sheet. Not attempted: reported open.
    if (twiceSignedArea(image.polygonOf(run)) > 0) {
      ++out.frame_holes;
      ++out.frame_holes_unclosable;
      out.unclosable_notes.push_back("frame hole of " + std::to_string(run.size()) +
                                     " boundary vertices not filled: it reaches the sky (no closing path along the frame), "
                                     "no closing path along the sky line passes over nearer pixels only, none joins it to "
                                     "the runs of other sheets around the occluder, and closed by its chord it encloses "
                                     "its own sheet");
      return;
    }
    addChordPieces(run, 0);
  }

  // A run closed by its chord. One that touches or crosses its chord (the foot of a facade along
  // the chord, with notches behind the poles standing on it) has no simple chord polygon: it is
  // cut where it meets the chord and each piece turning the hole's way is closed by its own
  // chord (the notches); the pieces turning the loop's way lie on the sheet and stay border.
  void addChordPieces(const VertexLoop& run, int depth) {
    const PixelPath polygon = image.polygonOf(run);
    const auto pieces = chordPieces(polygon);
    if (pieces.size() == 1) {
      appendHole(out, run, ClosedBy::Chord);
      ++out.frame_holes;
      if (depth > 0) ++out.frame_holes_chord_pieces;
      return;
    }
    if (depth == 0) ++out.frame_hole_runs_cut_at_chord;
    for (const auto& [first, last] : pieces) {
      if (last - first < 2) continue;
      const VertexLoop piece(run.begin() + static_cast<std::ptrdiff_t>(first),
                             run.begin() + static_cast<std::ptrdiff_t>(last) + 1);
      const PixelPath piece_polygon(polygon.begin() + static_cast<std::ptrdiff_t>(first),
                                    polygon.begin() + static_cast<std::ptrdiff_t>(last) + 1);
      if (!(twiceSignedArea(piece_polygon) < 0)) continue;
      if (depth < kMaxChordCutDepth) addChordPieces(piece, depth + 1);
    }
  }

  // Runs of non-border edges of a border loop, starting after a border edge, cut at their
  // vertices on the frame: each a frame hole candidate.
  void addRunsOf(const VertexLoop& loop, const std::vector<std::uint8_t>& border_edge) {
    const std::size_t n = loop.size();
    std::size_t first = 0;
    while (!border_edge[first]) ++first;
    for (std::size_t k = 1; k <= n;) {
      const std::size_t i = (first + k) % n;
      if (border_edge[i]) {
        ++k;
        continue;
      }
      std::size_t length = 0;  // edges in the run
      while (k + length <= n && !border_edge[(first + k + length) % n]) ++length;
      k += length;
      VertexLoop run;
      for (std::size_t e = 0; e <= length; ++e) {
        const auto v = loop[(i + e) % n];
        run.push_back(v);
        const bool cut = e == length || (e > 0 && image.frameSides(image.pixelOf(v)) != 0);
        if (!cut) continue;
        if (run.size() >= 3) addFrameHole(run);
        run = VertexLoop{v};
      }
    }
  }

  // Once every run is known: the pending runs joined with others, as backdrops, by their
  // chord, or reported unclosable.
  void closeRemaining() {
    RunChainer(image, pending, false).closeChains(out, nullptr);
    // The runs whose chord polygon encloses their own sheet: as a backdrop, or unclosable.
    for (auto& run : pending) {
      if (run.empty()) continue;
      if (twiceSignedArea(image.polygonOf(run)) > 0) enclosing.push_back(std::move(run)), run.clear();
    }
    // A run whose outline trace finds no other run's start (its end at a pocket of sky walled in
    // by thin far structures) would stop every chain through it: left out, the others' trace
    // passes over its pixels, and it stays open alone (a few rounds).
    for (int round = 0; backdrops != BackdropMode::Off && round < 4; ++round) {
      const std::int64_t closed_before = out.frame_holes_backdrop;
      std::vector<std::size_t> dead_ends;
      RunChainer(image, enclosing, true).closeChains(out, &dead_ends);
      if (out.frame_holes_backdrop > closed_before || dead_ends.empty()) break;
      std::sort(dead_ends.begin(), dead_ends.end());
      dead_ends.erase(std::unique(dead_ends.begin(), dead_ends.end()), dead_ends.end());
      for (const std::size_t r : dead_ends) pending.push_back(std::move(enclosing[r])), enclosing[r].clear();
    }
    for (auto& run : enclosing)
      if (!run.empty()) pending.push_back(std::move(run));
    for (std::size_t r = 0; r < pending.size(); ++r)
      if (!pending[r].empty()) addChordOrUnclosable(pending[r]);
  }
};

// The kind of a boundary loop; `border_edge` gets, per edge i -> i+1, whether it is a border edge.
LoopKind loopKind(const DepthImage& image, const VertexLoop& loop, std::vector<std::uint8_t>& border_edge) {
  const std::size_t n = loop.size();
  border_edge.assign(n, 0);
  bool any_border = false, any_pixel_less = false;
  double twice_area = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const auto a = loop[i], b = loop[(i + 1) % n];
    const OpenMesh::Vec2i pa = image.pixelOf(a), pb = image.pixelOf(b);
    // Vertices a frame hole's patch added along the frame or the sky line are part of the border.
    if (image.m.mesh.property(image.m.properties.origin, a) != static_cast<std::uint8_t>(VertexOrigin::Pixel) &&
        image.frameSides(pa) == 0 && !image.nextToNoDepth(pa))
      any_pixel_less = true;
    twice_area += double(pa[0]) * pb[1] - double(pb[0]) * pa[1];
    border_edge[i] = (image.frameSides(pa) & image.frameSides(pb)) != 0 ||
                     (image.nextToNoDepth(pa) && image.nextToNoDepth(pb));
    any_border = any_border || border_edge[i];
  }
  if (any_pixel_less) return LoopKind::Hole;  // a loop through added vertices: not from the image grid
  if (twice_area < 0) return any_border ? LoopKind::SkyOpening : LoopKind::Hole;
  return any_border ? LoopKind::Border : (twice_area == 0 ? LoopKind::Hole : LoopKind::Silhouette);
}

}  // namespace

std::vector<std::pair<std::size_t, std::size_t>> chordPieces(const std::vector<OpenMesh::Vec2i>& path) {
  const std::size_t n = path.size();
  if (n < 2) return {};
  const std::int64_t ax = path.front()[0], ay = path.front()[1];
  const std::int64_t bx = path.back()[0], by = path.back()[1];
  const auto orient = [](std::int64_t px, std::int64_t py, std::int64_t qx, std::int64_t qy, std::int64_t rx,
                         std::int64_t ry) { return (qx - px) * (ry - py) - (qy - py) * (rx - px); };
  const auto sign = [](std::int64_t x) { return (x > 0) - (x < 0); };
  const std::int64_t length2 = (bx - ax) * (bx - ax) + (by - ay) * (by - ay);
  std::vector<std::int64_t> side(n);
  for (std::size_t i = 0; i < n; ++i) side[i] = orient(ax, ay, bx, by, path[i][0], path[i][1]);
  std::vector<std::size_t> cuts{0};
  for (std::size_t i = 1; i + 1 < n; ++i) {
    const std::int64_t along = (path[i][0] - ax) * (bx - ax) + (path[i][1] - ay) * (by - ay);
    if (side[i] == 0 && along >= 0 && along <= length2) cuts.push_back(i);
  }
  for (std::size_t i = 0; i + 1 < n; ++i) {
    if (sign(side[i]) * sign(side[i + 1]) >= 0) continue;
    const auto& p = path[i];
    const auto& q = path[i + 1];
    if (sign(orient(p[0], p[1], q[0], q[1], ax, ay)) * sign(orient(p[0], p[1], q[0], q[1], bx, by)) >= 0) continue;
    const std::size_t nearer = std::abs(side[i]) <= std::abs(side[i + 1]) ? i : i + 1;
    if (nearer > 0 && nearer + 1 < n) cuts.push_back(nearer);
  }
  cuts.push_back(n - 1);
  std::sort(cuts.begin(), cuts.end());
  cuts.erase(std::unique(cuts.begin(), cuts.end()), cuts.end());
  std::vector<std::pair<std::size_t, std::size_t>> pieces;
  for (std::size_t k = 0; k + 1 < cuts.size(); ++k) pieces.emplace_back(cuts[k], cuts[k + 1]);
  return pieces;
}

std::vector<VertexLoop> findBoundaryLoops(const SurfaceMesh& mesh) {
  std::vector<VertexLoop> loops;
  std::vector<std::uint8_t> visited(mesh.n_halfedges(), 0);
  for (const auto start : mesh.halfedges()) {
    if (visited[start.idx()] || mesh.status(mesh.edge_handle(start)).deleted() || !mesh.is_boundary(start)) continue;
    VertexLoop cycle;
    OpenMesh::HalfedgeHandle h = start;
    while (h.is_valid() && !visited[h.idx()]) {
      visited[h.idx()] = 1;
      cycle.push_back(mesh.from_vertex_handle(h));
      h = mesh.next_halfedge_handle(h);
    }
    // Split at repeated vertices: a -> ... -> v -> x ... -> v -> ... becomes (v x ...) and the rest.
    VertexLoop stack;
    std::unordered_map<int, std::size_t> position;
    for (const auto v : cycle) {
      const auto found = position.find(v.idx());
      if (found == position.end()) {
        position.emplace(v.idx(), stack.size());
        stack.push_back(v);
        continue;
      }
      const std::size_t at = found->second;
      VertexLoop sub(stack.begin() + static_cast<std::ptrdiff_t>(at), stack.end());
      for (std::size_t k = at + 1; k < stack.size(); ++k) position.erase(stack[k].idx());
      stack.resize(at + 1);
      if (sub.size() >= 3) loops.push_back(std::move(sub));
    }
    if (stack.size() >= 3) loops.push_back(std::move(stack));
  }
  return loops;
}

const char* loopKindName(LoopKind kind) {
  switch (kind) {
    case LoopKind::Hole: return "hole";
    case LoopKind::SkyOpening: return "sky_opening";
    case LoopKind::Border: return "border";
    case LoopKind::Silhouette: return "silhouette";
  }
  return "unknown";
}

DepthLoops classifyDepthLoops(const DepthMesh& m, const cv::Mat& had_depth, const cv::Mat& depth_m,
                              BackdropMode backdrops) {
  DepthLoops out;
  out.loops = findBoundaryLoops(m.mesh);
  const DepthImage image(m, had_depth, depth_m);
  FrameHoleCloser frame_holes{image, backdrops, out, {}, {}};
  for (const VertexLoop& loop : out.loops) {
    std::vector<std::uint8_t> border_edge;
    const LoopKind kind = loopKind(image, loop, border_edge);
    out.kinds.push_back(kind);
    switch (kind) {
      case LoopKind::Hole:
        ++out.inner_holes;
        appendHole(out, loop, ClosedBy::Path, {}, {}, false);
        break;
      case LoopKind::SkyOpening: ++out.sky_openings; break;
      case LoopKind::Silhouette: ++out.silhouettes; break;
      case LoopKind::Border:
        ++out.border_loops;
        frame_holes.addRunsOf(loop, border_edge);
        break;
    }
  }
  frame_holes.closeRemaining();
  return out;
}

}  // namespace solo
