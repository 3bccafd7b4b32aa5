#include "solo/geometry/mesh_cleanup.h"

#include "solo/geometry/boundary_loops.h"
#include "solo/core/error.h"
#include "solo/geometry/foreground_solids.h"
#include "solo/geometry/mesh_fragments.h"
#include "solo/geometry/mesh_holes.h"
#include "solo/geometry/mesh_repair.h"
#include "solo/core/scene.h"

#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <future>
#include <optional>

namespace solo {
namespace {

cv::Mat hadDepthMask(const DepthMesh& m) {
  cv::Mat mask(m.height, m.width, CV_8U);
  for (int v = 0; v < m.height; ++v)
    for (int u = 0; u < m.width; ++u) mask.at<std::uint8_t>(v, u) = m.vertexAt(u, v) >= 0 ? 1 : 0;
  return mask;
}

void rebuildPixelIndex(DepthMesh& m) {
  std::fill(m.vertex_of_pixel.begin(), m.vertex_of_pixel.end(), -1);
  for (const auto v : m.mesh.vertices()) {
    if (m.mesh.property(m.properties.origin, v) != static_cast<std::uint8_t>(VertexOrigin::Pixel)) continue;
    const OpenMesh::Vec2i p = m.mesh.property(m.properties.pixel, v);
    m.vertex_of_pixel[static_cast<std::size_t>(p[1]) * m.width + p[0]] = v.idx();
  }
}

std::int64_t liveFaceCount(const SurfaceMesh& mesh) {
  std::int64_t n = 0;
  for (const auto f : mesh.faces()) n += !mesh.status(f).deleted();
  return n;
}

void addLoopCounts(StageReport& report, const std::string& prefix, const DepthLoops& loops) {
  report.add(prefix + "boundary_loops", static_cast<std::int64_t>(loops.loops.size()));
  report.add(prefix + "border_loops", loops.border_loops);
  report.add(prefix + "sky_openings", loops.sky_openings);
  report.add(prefix + "silhouette_loops", loops.silhouettes);
  report.add(prefix + "inner_holes", loops.inner_holes);
  report.add(prefix + "frame_holes", loops.frame_holes);
  report.add(prefix + "frame_holes_unclosable", loops.frame_holes_unclosable);
  report.add(prefix + "frame_holes_sky_line", loops.frame_holes_sky_line);
  report.add(prefix + "frame_holes_merged", loops.frame_holes_merged);
  report.add(prefix + "frame_hole_runs_merged", loops.frame_hole_runs_merged);
  report.add(prefix + "frame_holes_backdrop", loops.frame_holes_backdrop);
  report.add(prefix + "frame_hole_runs_backdrop", loops.frame_hole_runs_backdrop);
  report.add(prefix + "frame_hole_runs_cut_at_chord", loops.frame_hole_runs_cut_at_chord);
  report.add(prefix + "frame_holes_chord_pieces", loops.frame_holes_chord_pieces);
}

// Room (metres) a backdrop leaves behind a foreground solid's back, beyond its thickness.
constexpr double kBackdropSolidRoom_m = 0.25;

// What a backdrop stays behind (CV_32F maps, metres, 0 for none): `farthest`, the farthest
// surface at each pixel centre, with the room the foreground solids and floating slabs closed
// after it will take (their thickness plus kBackdropSolidRoom_m); `observed`, the depth
// observed where the mesh shows nothing (the removed surface). `farthest_surface`, when given,
// is the mesh's farthestSurfaceDepth, found beforehand.
void backdropDepthBounds(const DepthMesh& m, const cv::Mat& depth_m, const cv::Mat& had_depth,
                         const DepthMeshCleanupOptions& options, cv::Mat& farthest, cv::Mat& observed,
                         const cv::Mat* farthest_surface = nullptr) {
  const SurfaceMesh& mesh = m.mesh;
  farthest = farthest_surface ? farthest_surface->clone() : farthestSurfaceDepth(mesh, m.camera, m.width, m.height);
  std::vector<int> sheet_of_vertex;
  std::vector<std::uint8_t> floating;
  if (options.close_solids && options.solids.floating_sheet_thickness_m > 0) {
    int count = 0;
    const std::vector<int> component = faceComponents(mesh, &count);
    floating = floatingSheets(m, component, count);
    sheet_of_vertex.assign(mesh.n_vertices(), -1);
    for (const auto f : mesh.faces())
      if (component[f.idx()] >= 0)
        for (const auto v : mesh.fv_range(f)) sheet_of_vertex[v.idx()] = component[f.idx()];
  }
  if (options.close_solids)
    cv::parallel_for_(cv::Range(0, m.height), [&](const cv::Range& rows) {
      for (int v = rows.start; v < rows.end; ++v)
        for (int u = 0; u < m.width; ++u) {
          const int i = m.vertexAt(u, v);
          if (i < 0 || mesh.status(OpenMesh::VertexHandle(i)).deleted()) continue;
          double t = classThicknessM(
              cityscapesClassOfInstance(mesh.property(m.properties.instance, OpenMesh::VertexHandle(i))));
          if (t <= 0 && !floating.empty() && sheet_of_vertex[i] >= 0 && floating[sheet_of_vertex[i]])
            t = options.solids.floating_sheet_thickness_m;
          if (t <= 0) continue;
          float& slot = farthest.at<float>(v, u);
          slot = std::max(slot,
                          static_cast<float>(mesh.point(OpenMesh::VertexHandle(i))[2] + t + kBackdropSolidRoom_m));
        }
    });
  observed = cv::Mat(m.height, m.width, CV_32F, cv::Scalar(0.0f));
  for (int v = 0; v < m.height; ++v)
    for (int u = 0; u < m.width; ++u) {
      const float z = depth_m.at<float>(v, u);
      if (had_depth.at<std::uint8_t>(v, u) && std::isfinite(z) && z > 0 && !(farthest.at<float>(v, u) > 0))
        observed.at<float>(v, u) = z;
    }
}

// Adds a second closeHoles pass (its holes listed after the first's).
void appendHoleClosing(HoleClosing& into, const HoleClosing& more) {
  into.holes += more.holes, into.filled += more.filled, into.left_open += more.left_open;
  into.by_image_space += more.by_image_space, into.by_refine_fair += more.by_refine_fair;
  into.by_triangulation += more.by_triangulation, into.by_centroid_fan += more.by_centroid_fan;
  into.by_membrane += more.by_membrane, into.by_chord_split += more.by_chord_split;
  into.patches_rejected_for_intersection += more.patches_rejected_for_intersection;
  into.faces_added += more.faces_added, into.vertices_added += more.vertices_added;
  into.largest_hole_vertices = std::max(into.largest_hole_vertices, more.largest_hole_vertices);
  into.warnings.insert(into.warnings.end(), more.warnings.begin(), more.warnings.end());
  into.patch_faces.insert(into.patch_faces.end(), more.patch_faces.begin(), more.patch_faces.end());
  into.hole_methods.insert(into.hole_methods.end(), more.hole_methods.begin(), more.hole_methods.end());
  into.hole_faces.insert(into.hole_faces.end(), more.hole_faces.begin(), more.hole_faces.end());
}

void addHoleCounts(StageReport& report, const HoleClosing& holes) {
  report.add("holes_filled", holes.filled);
  report.add("holes_left_open", holes.left_open);
  report.add("holes_filled_refine_fair", holes.by_refine_fair);
  report.add("holes_filled_triangulation_only", holes.by_triangulation);
  report.add("holes_filled_centroid_fan", holes.by_centroid_fan);
  report.add("holes_filled_image_space", holes.by_image_space);
  report.add("hole_patches_rejected_intersecting", holes.patches_rejected_for_intersection);
  report.add("hole_faces_added", holes.faces_added);
  report.add("hole_vertices_added", holes.vertices_added);
  report.add("largest_hole_vertices", holes.largest_hole_vertices);
  for (const auto& w : holes.warnings) report.notes.push_back(w);
}

// Deletes the spurious faces, marking the pixels of their corners with the criteria that
// removed them (m.removed_spurious), and reports how many each criterion found.
void removeSpuriousFaces(StageReport& report, DepthMesh& m, const SpuriousFaceResult& spurious) {
  SurfaceMesh& mesh = m.mesh;
  m.removed_spurious = cv::Mat::zeros(m.height, m.width, CV_8U);
  for (const auto f : mesh.faces()) {
    if (!spurious.spurious[f.idx()]) continue;
    for (const auto v : mesh.fv_range(f)) {
      const OpenMesh::Vec2i p = mesh.property(m.properties.pixel, v);
      if (p[0] >= 0 && p[1] >= 0 && p[0] < m.width && p[1] < m.height)
        m.removed_spurious.at<std::uint8_t>(p[1], p[0]) |= spurious.criteria[f.idx()];
    }
    mesh.delete_face(f, true);
  }
  report.add("spurious_faces_removed", spurious.removed);
  report.add("spurious_by_depth_jump", spurious.by_depth_jump);
  report.add("spurious_by_grazing_angle", spurious.by_grazing);
  report.add("spurious_by_uncertain_mask", spurious.by_uncertain);
  report.add("spurious_by_instance_boundary", spurious.by_instance_boundary);
}

// Scores the removal against the ground truth: the occlusion criteria alone, then every criterion.
void addSpuriousScores(StageReport& report, const SpuriousFaceResult& spurious,
                       const std::vector<std::uint8_t>& spurious_truth) {
  std::vector<std::uint8_t> occlusion(spurious.criteria.size());
  for (std::size_t i = 0; i < occlusion.size(); ++i) occlusion[i] = (spurious.criteria[i] & kOcclusionCriteria) != 0;
  const DetectionScore score = scoreDetection(occlusion, spurious_truth);
  const DetectionScore all = scoreDetection(spurious.spurious, spurious_truth);
  report.add("spurious_truth_faces", score.true_positives + score.false_negatives);
  report.add("spurious_true_positives", score.true_positives);
  report.add("spurious_false_positives", score.false_positives);
  report.add("spurious_false_negatives", score.false_negatives);
  report.add("spurious_precision", score.precision);
  report.add("spurious_recall", score.recall);
  report.add("removal_precision_with_instance_cut", all.precision);
  report.add("removal_recall_with_instance_cut", all.recall);
}

// Removes the small components, resolves pinched vertices, then removes the components that left.
void removeFragments(StageReport& report, SurfaceMesh& mesh, std::int64_t min_fragment_faces) {
  const FragmentRemoval fragments = removeSmallComponents(mesh, min_fragment_faces);
  const PinchResolution pinches = resolvePinchedVertices(mesh);
  const FragmentRemoval fragments_after_pinches = removeSmallComponents(mesh, min_fragment_faces);
  report.add("fragments_removed", fragments.components_removed + fragments_after_pinches.components_removed);
  report.add("fragment_faces_removed", fragments.faces_removed + fragments_after_pinches.faces_removed);
  report.add("pinched_vertices", pinches.pinched_vertices);
  report.add("pinch_faces_removed", pinches.faces_removed);
}

// A frame hole closed along the sky line: its 3D fallbacks close it by its chord, which is
// hopeless when the chord polygon encloses its own sheet (positive area in the image).
bool chordEnclosesSheet(const DepthMesh& m, const VertexLoop& run) {
  double twice = 0;
  for (std::size_t q = 0; q < run.size(); ++q) {
    const OpenMesh::Vec2i p0 = m.mesh.property(m.properties.pixel, run[q]);
    const OpenMesh::Vec2i p1 = m.mesh.property(m.properties.pixel, run[(q + 1) % run.size()]);
    twice += double(p0[0]) * p1[1] - double(p1[0]) * p0[1];
  }
  return twice > 0;
}

// Whether hole i of `source` gets the image-space fill only. A large frame hole closed by its
// chord whose image-space patch fails gets no 3D method: its chord crosses the mesh, and every
// 3D patch failed on such holes (measured on the synthetic 1080p streets: 0 of 11, 506 to 3 689
// boundary vertices), after seconds of CGAL. Nor does a sky-line hole whose chord encloses its sheet,
// nor a large frame hole that a backdrop closes when its own closing fails (`backdrop_retry`).
bool imageSpaceOnly(const DepthMesh& m, const DepthMeshCleanupOptions& options, const DepthLoops& source,
                    std::size_t i, bool backdrop_retry) {
  const bool large = static_cast<int>(source.holes[i].size()) > options.hole_filling.max_cubic_boundary_vertices;
  return ((source.chord_closed[i] || source.sky_line_closed[i]) && large) ||
         (backdrop_retry && source.frame_hole[i] && !source.backdrop[i] && large) ||
         (source.sky_line_closed[i] && chordEnclosesSheet(m, source.holes[i])) ||
         source.merged[i];  // its runs belong to several sheets: no chord closes it
}

// Closes the holes `which` of `source` (backdrops stay behind `farthest` and `observed` when given;
// `backdrop_retry`: the frame holes left open are tried again as backdrops).
HoleClosing closeSomeHoles(DepthMesh& m, const DepthMeshCleanupOptions& options, const DepthLoops& source,
                           const std::vector<std::size_t>& which, const cv::Mat* farthest, const cv::Mat* observed,
                           bool backdrop_retry) {
  DepthLoops subset;
  std::vector<std::uint8_t> only;
  for (const std::size_t i : which) {
    subset.holes.push_back(source.holes[i]);
    subset.frame_paths.push_back(source.frame_paths[i]);
    subset.path_after.push_back(source.path_after[i]);
    subset.backdrop.push_back(source.backdrop[i]);
    only.push_back(imageSpaceOnly(m, options, source, i, backdrop_retry));
  }
  PixelMapping mapping{m.properties, m.camera, m.width, m.height, &m.vertex_of_pixel};
  mapping.frame_paths = &subset.frame_paths;
  mapping.frame_path_after = &subset.path_after;
  mapping.image_space_only = &only;
  mapping.backdrop = &subset.backdrop;
  mapping.farthest_surface_m = farthest;
  mapping.observed_depth_m = observed;
  return closeHoles(m.mesh, subset.holes, options.hole_filling, mapping);
}

// The backdrops `which` of `source`, behind the mesh's farthest surfaces (`farthest_surface`:
// found beforehand, or none).
HoleClosing closeBackdrops(DepthMesh& m, const cv::Mat& depth_m, const cv::Mat& had_depth,
                           const DepthMeshCleanupOptions& options, const DepthLoops& source,
                           const std::vector<std::size_t>& which, const cv::Mat* farthest_surface = nullptr) {
  cv::Mat farthest, observed;
  backdropDepthBounds(m, depth_m, had_depth, options, farthest, observed, farthest_surface);
  return closeSomeHoles(m, options, source, which, &farthest, &observed, false);
}

// Takes the patches of `own` (indices into the first pass's holes) out of the mesh; returns the
// vertices that went with them.
std::int64_t removeHolePatches(DepthMesh& m, const HoleClosing& first, const std::vector<std::size_t>& own) {
  std::vector<OpenMesh::VertexHandle> touched;
  for (const std::size_t k : own)
    for (const auto f : first.hole_faces[k]) {
      if (m.mesh.status(f).deleted()) continue;
      for (const auto v : m.mesh.fv_range(f)) touched.push_back(v);
      m.mesh.delete_face(f, true);
    }
  std::sort(touched.begin(), touched.end());
  touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
  std::int64_t removed = 0;
  for (const auto v : touched) removed += m.mesh.status(v).deleted();
  return removed;
}

// Counts a first-pass patch taken out: its hole is closed inside a backdrop instead.
void uncountPatch(HoleClosing& first, std::size_t k) {
  const std::string& method = first.hole_methods[k];
  if (method == "image_space") --first.by_image_space;
  else if (method == "refine_fair") --first.by_refine_fair;
  else if (method == "triangulation") --first.by_triangulation;
  else if (method == "centroid_fan") --first.by_centroid_fan;
  --first.holes, --first.filled;
  first.faces_added -= static_cast<std::int64_t>(first.hole_faces[k].size());
  first.hole_methods[k] = "backdrop";
  first.hole_faces[k].clear();
}

// The first pass's frame holes closed on their own (indices into its holes).
std::vector<std::size_t> ownFrameHolePatches(const DepthLoops& loops, const std::vector<std::size_t>& first_pass,
                                             const HoleClosing& first) {
  std::vector<std::size_t> own;
  for (std::size_t k = 0; k < first_pass.size(); ++k)
    if (loops.frame_hole[first_pass[k]] && first.hole_methods[k] != "open" && !first.hole_faces[k].empty())
      own.push_back(k);
  return own;
}

// The backdrops closed again on a mesh (a copy, or the mesh itself when the first backdrops
// are closed on a copy) with the patches of the frame holes closed on their own taken out,
// every frame hole a backdrop run.
struct BackdropJoin {
  DepthMesh& mesh;
  bool tried = false;  // the joined classification had a backdrop to close
  HoleClosing backdrops;
  std::int64_t vertices_removed = 0;

  explicit BackdropJoin(DepthMesh& on) : mesh(on) {}

  // `farthest_surface`: the mesh's farthestSurfaceDepth without the patches, or none.
  void run(const cv::Mat& depth_m, const cv::Mat& had_depth, const DepthMeshCleanupOptions& options,
           const HoleClosing& first, const std::vector<std::size_t>& own, const cv::Mat* farthest_surface = nullptr) {
    vertices_removed = removeHolePatches(mesh, first, own);
    const DepthLoops joined = classifyDepthLoops(mesh, had_depth, depth_m, BackdropMode::EveryFrameHole);
    std::vector<std::size_t> joined_backdrops;
    for (std::size_t i = 0; i < joined.holes.size(); ++i)
      if (joined.backdrop[i]) joined_backdrops.push_back(i);
    if (joined_backdrops.empty()) return;
    backdrops = closeBackdrops(mesh, depth_m, had_depth, options, joined, joined_backdrops, farthest_surface);
    tried = true;
  }

  // Whether it leaves fewer holes open than the backdrops `more` (counted in the report).
  bool better(const HoleClosing& more, const std::vector<std::size_t>& own, StageReport& report) const {
    if (!tried) return false;
    report.add("frame_holes_tried_in_backdrops", static_cast<std::int64_t>(own.size()));
    return backdrops.left_open < more.left_open;
  }
};

// Takes the join's counts: `first` (the first pass) loses the patches taken out, `more` (the
// backdrops) becomes the join's; `m` holds the join's mesh.
void adoptBackdropJoin(const DepthMesh& m, BackdropJoin& join, const std::vector<std::size_t>& own,
                       HoleClosing& first, HoleClosing& more, StageReport& report) {
  for (const std::size_t k : own) uncountPatch(first, k);
  first.vertices_added -= join.vertices_removed;
  first.patch_faces.erase(std::remove_if(first.patch_faces.begin(), first.patch_faces.end(),
                                         [&m](OpenMesh::FaceHandle f) { return m.mesh.status(f).deleted(); }),
                          first.patch_faces.end());
  more = std::move(join.backdrops);
  report.add("frame_holes_joined_to_backdrops", static_cast<std::int64_t>(own.size()));
}

// Whether a frame hole of `own` (indices into the first pass) closed along the image frame has
// a loop vertex on or beside (8-neighbourhood) a pixel of the backdrops' polygons (their runs
// and closing paths): the patch of such a hole reaches from the frame to where the backdrop
// passes.
bool ownFrameHolesBesideBackdrops(const DepthMesh& m, const DepthLoops& loops,
                                  const std::vector<std::size_t>& backdrop_holes,
                                  const std::vector<std::size_t>& first_pass, const std::vector<std::size_t>& own) {
  cv::Mat polygon(m.height, m.width, CV_8U, cv::Scalar(0));
  const auto mark = [&](const OpenMesh::Vec2i& p) {
    if (p[0] >= 0 && p[1] >= 0 && p[0] < m.width && p[1] < m.height) polygon.at<std::uint8_t>(p[1], p[0]) = 1;
  };
  for (const std::size_t b : backdrop_holes) {
    for (const auto v : loops.holes[b]) mark(m.mesh.property(m.properties.pixel, v));
    for (const auto& p : loops.frame_paths[b]) mark(p);
  }
  cv::dilate(polygon, polygon, cv::Mat::ones(3, 3, CV_8U));
  for (const std::size_t k : own) {
    if (loops.frame_paths[first_pass[k]].empty()) continue;
    for (const auto v : loops.holes[first_pass[k]]) {
      const OpenMesh::Vec2i p = m.mesh.property(m.properties.pixel, v);
      if (p[0] >= 0 && p[1] >= 0 && p[0] < m.width && p[1] < m.height && polygon.at<std::uint8_t>(p[1], p[0]))
        return true;
    }
  }
  return false;
}

struct MeshSize {
  std::size_t vertices, edges, faces;
  bool operator==(const MeshSize& o) const { return vertices == o.vertices && edges == o.edges && faces == o.faces; }
};

MeshSize meshSize(const SurfaceMesh& mesh) { return {mesh.n_vertices(), mesh.n_edges(), mesh.n_faces()}; }

// The join tried after the backdrops `more` closed on the mesh, when they left a hole open.
void joinAfterBackdrops(DepthMesh& m, const cv::Mat& depth_m, const cv::Mat& had_depth,
                        const DepthMeshCleanupOptions& options, const std::vector<std::size_t>& own,
                        HoleClosing& first, HoleClosing& more, StageReport& report) {
  if (more.left_open == 0 || own.empty()) return;
  DepthMesh trial = m;
  BackdropJoin join(trial);
  join.run(depth_m, had_depth, options, first, own);
  if (!join.better(more, own, report)) return;
  m = trial;
  adoptBackdropJoin(m, join, own, first, more, report);
}

// The backdrops and the join side by side: the backdrops on a copy taken first, the join on the
// mesh itself (with its farthest surfaces without the patches, found while the copy is made; it
// changes the mesh only once the copy is taken). Then what the one-after-the-other order does:
// the join kept when the backdrops left a hole open and added nothing (else tried again after
// them), otherwise the copy becomes the mesh.
HoleClosing closeBackdropsBesideJoin(DepthMesh& m, const cv::Mat& depth_m, const cv::Mat& had_depth,
                                     const DepthMeshCleanupOptions& options, const DepthLoops& loops,
                                     const std::vector<std::size_t>& backdrop_holes,
                                     const std::vector<std::size_t>& own, HoleClosing& first, StageReport& report) {
  std::optional<DepthMesh> copy;
  std::promise<void> copied;
  std::shared_future<void> copy_taken = copied.get_future().share();
  BackdropJoin join(m);
  std::future<void> beside = std::async(std::launch::async, [&] {
    std::vector<std::uint8_t> patch_face(m.mesh.n_faces(), 0);
    for (const std::size_t k : own)
      for (const auto f : first.hole_faces[k]) patch_face[f.idx()] = 1;
    const cv::Mat farthest_surface = farthestSurfaceDepth(m.mesh, m.camera, m.width, m.height, &patch_face);
    copy_taken.get();
    join.run(depth_m, had_depth, options, first, own, &farthest_surface);
  });
  try {
    copy.emplace(m);
  } catch (...) {
    copied.set_exception(std::current_exception());
    throw;
  }
  copied.set_value();
  const MeshSize before = meshSize(copy->mesh);
  HoleClosing more = closeBackdrops(*copy, depth_m, had_depth, options, loops, backdrop_holes);
  beside.get();
  const bool unchanged = meshSize(copy->mesh) == before && more.faces_added == 0;
  if (more.left_open > 0 && unchanged && join.better(more, own, report)) {
    adoptBackdropJoin(m, join, own, first, more, report);
    return more;
  }
  m = *copy;
  if (!unchanged) joinAfterBackdrops(m, depth_m, had_depth, options, own, first, more, report);
  return more;
}

// The backdrops of the first classification (`backdrop_holes` of `loops`). One whose patch
// meets the mesh may have frame holes beside it that closed on their own with patches where it
// has to pass (behind a lamp pole one pixel wide at the mesh's size, the runs on both sides of
// the pole closed along the frame behind it): then the backdrops are closed again on a copy of
// the mesh without those patches (BackdropJoin), kept when it leaves fewer holes open. When one
// of them closed along the image frame touches a backdrop's polygon and there is more than one
// thread, the two run side by side (closeBackdropsBesideJoin), with the same mesh as a result.
HoleClosing closeFirstBackdrops(DepthMesh& m, const cv::Mat& depth_m, const cv::Mat& had_depth,
                                const DepthMeshCleanupOptions& options, const DepthLoops& loops,
                                const std::vector<std::size_t>& backdrop_holes,
                                const std::vector<std::size_t>& first_pass, HoleClosing& first, StageReport& report) {
  const std::vector<std::size_t> own = ownFrameHolePatches(loops, first_pass, first);
  const bool beside_backdrops = !own.empty() && cv::getNumThreads() >= 2 &&
                                ownFrameHolesBesideBackdrops(m, loops, backdrop_holes, first_pass, own);
  report.add("backdrop_join_beside", beside_backdrops);
  if (beside_backdrops)
    return closeBackdropsBesideJoin(m, depth_m, had_depth, options, loops, backdrop_holes, own, first, report);
  HoleClosing more = closeBackdrops(m, depth_m, had_depth, options, loops, backdrop_holes);
  joinAfterBackdrops(m, depth_m, had_depth, options, own, first, more, report);
  return more;
}

// Closes the holes of a depth mesh. Backdrops are filled after every other hole: they lie
// behind everything in their region, the other holes' patches too (seen through the
// farthest-surface map).
HoleClosing closeDepthHoles(DepthMesh& m, const cv::Mat& depth_m, const cv::Mat& had_depth,
                            const DepthMeshCleanupOptions& options, const DepthLoops& loops,
                            BackdropMode backdrop_mode, StageReport& report) {
  std::vector<std::size_t> first_pass, backdrop_holes;
  for (std::size_t i = 0; i < loops.holes.size(); ++i)
    (loops.backdrop[i] ? backdrop_holes : first_pass).push_back(i);
  HoleClosing holes =
      closeSomeHoles(m, options, loops, first_pass, nullptr, nullptr, backdrop_mode != BackdropMode::Off);
  // A frame hole its own closing left open (its patch met the mesh) is tried again in a
  // backdrop: the loops are classified again, every frame hole left a backdrop run.
  std::int64_t retried = 0;
  for (std::size_t k = 0; k < first_pass.size(); ++k)
    retried += loops.frame_hole[first_pass[k]] && holes.hole_methods[k] == "open";
  DepthLoops again;
  const DepthLoops* backdrop_source = &loops;
  if (retried > 0 && backdrop_mode != BackdropMode::Off) {
    again = classifyDepthLoops(m, had_depth, depth_m, BackdropMode::EveryFrameHole);
    std::vector<std::size_t> again_backdrops;
    for (std::size_t i = 0; i < again.holes.size(); ++i)
      if (again.backdrop[i]) again_backdrops.push_back(i);
    // No chain of the new classification closes: the backdrops found first are closed as they
    // were (the frame holes left open stay open, with their notes).
    if (!again_backdrops.empty()) {
      backdrop_source = &again;
      backdrop_holes = std::move(again_backdrops);
    }
    report.add("frame_holes_retried_as_backdrop", retried);
    report.add("backdrop_runs_after_retry", again.frame_hole_runs_backdrop);
  }
  if (!backdrop_holes.empty()) {
    const Stopwatch backdrop_clock;
    HoleClosing more =
        backdrop_source == &loops
            ? closeFirstBackdrops(m, depth_m, had_depth, options, loops, backdrop_holes, first_pass, holes, report)
            : closeBackdrops(m, depth_m, had_depth, options, again, backdrop_holes);
    if (backdrop_source == &again && more.left_open == 0) {
      // The frame holes left open are closed now, inside the backdrops (counted there).
      holes.holes -= retried;
      holes.left_open -= retried;
    }
    appendHoleClosing(holes, more);
    report.add("seconds_backdrops", backdrop_clock.seconds(), "s");  // part of seconds_hole_filling
  }
  addHoleCounts(report, holes);
  return holes;
}

// Closes the foreground solids and floating sheets (without instances: the floating sheets only).
void closeSolids(StageReport& report, DepthMesh& m, const HoleClosing& holes, const DepthMeshCleanupOptions& options) {
  const SolidClosing solids = closeForegroundSolids(m, holes.patch_faces, options.solids);
  report.add("foreground_sheets_considered", solids.sheets);
  report.add("foreground_solids", solids.solids);
  report.add("solid_faces_added", solids.faces_added);
  report.add("solid_back_vertices_clamped", solids.vertices_clamped);
  report.add("floating_sheets_closed", solids.floating_sheets);
  std::string classes;
  for (const auto& c : solids.classes) classes += (classes.empty() ? "" : " ") + c;
  report.add("foreground_solids_per_class", classes);
}

}  // namespace

void addMeshCounts(StageReport& report, const std::string& prefix, const MeshMetrics& m) {
  report.add(prefix + "vertices", m.vertices);
  report.add(prefix + "faces", m.faces);
  report.add(prefix + "unreferenced_vertices", m.unreferenced_vertices);
  report.add(prefix + "components", m.components);
  report.add(prefix + "boundary_loops_total", m.boundary_loops);
  report.add(prefix + "boundary_edges", m.boundary_edges);
  report.add(prefix + "non_manifold_edges", m.non_manifold_edges);
  report.add(prefix + "non_manifold_vertices", m.non_manifold_vertices);
  report.add(prefix + "self_intersecting_pairs", m.self_intersecting_pairs);
  report.add(prefix + "degenerate_faces", m.degenerate_faces);
  report.add(prefix + "closed", isWatertight(m));
}

StageReport cleanDepthMesh(DepthMesh& m, const cv::Mat& depth_m, const cv::Mat& instances, const cv::Mat& uncertain,
                           const DepthMeshCleanupOptions& options, const std::vector<std::uint8_t>* spurious_truth,
                           const cv::Mat& normals) {
  StageReport report;
  report.name = "mesh";
  const Stopwatch total;
 
  SurfaceMesh& mesh = m.mesh;
  const cv::Mat had_depth = hadDepthMask(m);
  m.had_depth = had_depth;
  report.add("depth_width", std::int64_t{m.width}, "px").add("depth_height", std::int64_t{m.height}, "px");
  report.add("before_vertices", static_cast<std::int64_t>(mesh.n_vertices()));
  report.add("before_faces", liveFaceCount(mesh));
  if (instances.empty())
    report.notes.push_back(
        "no instance map: no instance-boundary cut and no foreground solids (floating sheets are still closed)");
  if (uncertain.empty()) report.notes.push_back("no uncertain mask: uncertain criterion not applied");

  Stopwatch step;
  const SpuriousFaceResult spurious = findSpuriousFaces(m, depth_m, instances, uncertain, options.spurious, normals);
  report.add("spurious_normal_planes", !normals.empty() && options.spurious.use_normals);
  removeSpuriousFaces(report, m, spurious);
  report.add("seconds_spurious_faces", step.seconds(), "s");
  if (spurious_truth) addSpuriousScores(report, spurious, *spurious_truth);

  step = Stopwatch();
  removeFragments(report, mesh, options.min_fragment_faces);
  report.add("seconds_fragments", step.seconds(), "s");

  step = Stopwatch();
  const BackdropMode backdrop_mode =
      options.backdrops && options.fill_holes ? BackdropMode::Unclosable : BackdropMode::Off;
  const DepthLoops loops = classifyDepthLoops(m, had_depth, depth_m, backdrop_mode);
  addLoopCounts(report, "found_", loops);
  for (const auto& note : loops.unclosable_notes) report.notes.push_back(note);
  report.add("seconds_boundary_loops", step.seconds(), "s");

  HoleClosing holes;
  step = Stopwatch();
  if (options.fill_holes)
    holes = closeDepthHoles(m, depth_m, had_depth, options, loops, backdrop_mode, report);
  else
    report.notes.push_back("hole filling off: " + std::to_string(loops.holes.size()) + " holes left open");
  report.add("seconds_hole_filling", step.seconds(), "s");

  step = Stopwatch();
  if (options.close_solids) closeSolids(report, m, holes, options);
  report.add("seconds_solids", step.seconds(), "s");

  step = Stopwatch();
  const DepthLoops remaining = classifyDepthLoops(m, had_depth, depth_m, backdrop_mode);
  addLoopCounts(report, "after_", remaining);
  collectGarbage(mesh);
  rebuildPixelIndex(m);
  report.add("after_vertices_live", static_cast<std::int64_t>(mesh.n_vertices()));
  report.add("after_faces_live", static_cast<std::int64_t>(mesh.n_faces()));
  report.add("seconds_garbage_collection", step.seconds(), "s");

  if (options.evaluate) {
    step = Stopwatch();
    addMeshCounts(report, "after_", evaluateMesh(toTriangleMesh(mesh)));
    report.add("seconds_evaluation", step.seconds(), "s");
  } else {
    report.notes.push_back("evaluation off: no self-intersection or manifoldness counts");
  }
  report.seconds = total.seconds();
  return report;
}

DepthMesh meshFromScene(const cv::Mat& depth_m, const PinholeCamera& camera, const cv::Mat& instances,
                        const cv::Mat& uncertain, const DepthMeshCleanupOptions& options, StageReport& report,
                        const cv::Mat& true_depth_m, const cv::Mat& true_normals, const cv::Mat& normals) {
  const Stopwatch clock;
  cv::Mat ids, mask, normal_map;
  if (!instances.empty()) {
    if (instances.size() == depth_m.size()) ids = instances;
    else cv::resize(instances, ids, depth_m.size(), 0, 0, cv::INTER_NEAREST);
  }
  if (!uncertain.empty()) {
    if (uncertain.size() == depth_m.size()) mask = uncertain;
    else cv::resize(uncertain, mask, depth_m.size(), 0, 0, cv::INTER_NEAREST);
  }
  if (!normals.empty()) {
    if (normals.size() == depth_m.size()) normal_map = normals;
    else cv::resize(normals, normal_map, depth_m.size(), 0, 0, cv::INTER_NEAREST);
  }
 
  DepthMesh mesh = meshFromDepth(depth_m, camera, ids);
 
  const double build_seconds = clock.seconds();
  std::vector<std::uint8_t> truth;
  const bool scored = !true_depth_m.empty() && true_depth_m.size() == depth_m.size() && !true_normals.empty() &&
                      true_normals.size() == depth_m.size();
  if (scored) truth = spuriousFacesFromGroundTruth(mesh, true_depth_m, true_normals);
  report = cleanDepthMesh(mesh, depth_m, ids, mask, options, scored ? &truth : nullptr, normal_map);
  if (!true_depth_m.empty() && !scored)
    report.notes.push_back("ground truth not of the depth map's size (or without normals): spurious faces not scored");
  report.metrics.insert(report.metrics.begin(), Metric{"seconds_backprojection", build_seconds, "s"});
  report.seconds += build_seconds;
  return mesh;
}

namespace {

// Refuses a non-finite coordinate or a face index out of range, naming the file.
void checkMeshInput(const TriangleMesh& input, const std::filesystem::path& source) {
  for (const auto& v : input.vertices)
    if (!std::isfinite(v.x()) || !std::isfinite(v.y()) || !std::isfinite(v.z()))
      throw InputError(source, "mesh has a non-finite vertex coordinate");
  for (const auto& f : input.faces)
    for (const auto i : f)
      if (i >= input.vertices.size()) throw InputError(source, "a face refers to a vertex that does not exist");
}

void addSoupRepairCounts(StageReport& report, const SoupRepair& repair) {
  report.add("duplicate_points_merged", repair.duplicate_points_merged);
  report.add("coincident_corners_merged", repair.coincident_corners_merged);
  report.add("faces_with_repeated_corner_removed", repair.faces_with_repeated_corner_removed);
  report.add("duplicate_faces_removed", repair.duplicate_faces_removed);
  report.add("unreferenced_vertices_removed", repair.unreferenced_vertices_removed);
  report.add("faces_reoriented", repair.faces_reoriented);
  report.add("non_manifold_points_duplicated", repair.non_manifold_points_duplicated);
  report.add("coincident_boundary_vertices_merged", repair.coincident_boundary_vertices_merged);
  report.add("non_manifold_faces_removed", repair.non_manifold_faces_removed);
  report.add("degenerate_faces_flipped", repair.degenerate_faces_flipped);
  report.add("degenerate_faces_removed", repair.degenerate_faces_removed);
}

// Fills every boundary loop of a general mesh; the notes name the method of the 100 largest holes.
void fillMeshHoles(StageReport& report, SurfaceMesh& mesh, const MeshCleanupOptions& options) {
  const std::vector<VertexLoop> loops = findBoundaryLoops(mesh);
  report.add("holes_found", static_cast<std::int64_t>(loops.size()));
  if (!options.fill_holes) {
    report.notes.push_back("hole filling off: " + std::to_string(loops.size()) + " holes left open");
    return;
  }
  const HoleClosing closing = closeHoles(mesh, loops, options.hole_filling, std::nullopt, options.large_holes);
  addHoleCounts(report, closing);
  report.add("holes_filled_membrane", closing.by_membrane);
  report.add("holes_filled_chord_split", closing.by_chord_split);
  std::vector<std::size_t> order(loops.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return loops[a].size() > loops[b].size(); });
  for (std::size_t k = 0; k < order.size() && k < 100; ++k)
    report.notes.push_back("hole of " + std::to_string(loops[order[k]].size()) +
                           " boundary vertices: " + closing.hole_methods[order[k]]);
  collectGarbage(mesh);
}

// A number as printf's %.3g writes it.
std::string fraction(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", value);
  return buffer;
}

// Removes the self-intersections of `mesh` (repairSelfIntersections) and reports the step.
void repairIntersectionsStep(StageReport& report, TriangleMesh& mesh, const MeshCleanupOptions& options) {
  const Stopwatch step;
  const IntersectionRepair r = repairSelfIntersections(mesh, options.intersection_repair);
  report.add("intersection_repair_pairs_before", r.pairs_before);
  report.add("intersection_repair_pairs_after", r.pairs_after);
  report.add("intersection_repair_vertices_moved", r.vertices_moved);
  report.add("intersection_repair_rounds_kept", static_cast<std::int64_t>(r.rounds_kept));
  report.add("intersection_repair_rounds_refused", static_cast<std::int64_t>(r.rounds_refused));
  report.add("intersection_repair_faces_before", r.faces_before);
  report.add("intersection_repair_faces_after", r.faces_after);
  report.add("intersection_repair_time_limit_hit", r.time_limit_hit);
  report.add("seconds_intersection_repair", step.seconds(), "s");
  if (r.time_limit_hit)
    report.warnings.push_back("self-intersection repair stopped at its time limit of " +
                              fraction(options.intersection_repair.time_limit_s) + " s with " +
                              std::to_string(r.pairs_after) + " intersecting pairs left");
  else if (!r.repaired)
    report.notes.push_back("self-intersection repair: " + std::to_string(r.pairs_after) + " of " +
                           std::to_string(r.pairs_before) + " intersecting pairs left (" + r.failure + ")");
}

// Replaces `mesh` by its alpha wrap; false (mesh unchanged, a warning) when the wrap hit its limit.
bool wrapStep(StageReport& report, TriangleMesh& mesh, const MeshCleanupOptions& options) {
  const Wrap w = wrapMesh(mesh, options.wrapping);
  report.add("wrap_alpha", w.alpha).add("wrap_offset", w.offset);
  report.add("wrap_alpha_fraction", options.wrapping.alpha_fraction);
  report.add("wrap_offset_fraction", options.wrapping.offset_fraction);
  report.add("wrap_faces_in", w.faces_used);
  report.add("wrap_time_limit_hit", w.time_limit_hit);
  report.add("seconds_wrap", w.seconds, "s");
  if (w.time_limit_hit || w.mesh.faces.empty()) {
    report.warnings.push_back("the alpha wrap stopped at its time limit of " + fraction(options.wrapping.time_limit_s) +
                              " s: the mesh is written unwrapped");
    return false;
  }
  mesh = w.mesh;
  return true;
}

// How far (fraction of the bounding-box diagonal) a point of the input may end up from the
// output before a warning says so.
constexpr double kMaxSurfaceMoveFraction = 1e-3;

// One-sided and symmetric Hausdorff distances between input and output, as fractions of the
// input's bounding-box diagonal (measureMeshDistances, seeded).
void addSurfaceDistances(StageReport& report, const TriangleMesh& input, const TriangleMesh& output,
                         const MeshCleanupOptions& options) {
  const Stopwatch step;
  MeshDistanceOptions sampling;
  sampling.samples = options.distance_samples;
  sampling.seed = options.distance_seed;
  try {
    const MeshDistances d = measureMeshDistances(output, input, sampling, "output", "input");
    const double diagonal = d.reference_bbox_diagonal > 0 ? d.reference_bbox_diagonal : 1.0;
    report.add("input_bbox_diagonal", d.reference_bbox_diagonal);
    report.add("hausdorff_input_to_output_fraction", d.hausdorff_from_reference / diagonal);
    report.add("hausdorff_output_to_input_fraction", d.hausdorff_to_reference / diagonal);
    report.add("hausdorff_symmetric_fraction", d.hausdorff / diagonal);
    report.add("distance_samples_per_direction", d.samples_per_direction);
    if (d.hausdorff_from_reference > kMaxSurfaceMoveFraction * diagonal)
      report.warnings.push_back("the output departs from the input surface by up to " +
                                fraction(100 * d.hausdorff_from_reference / diagonal) +
                                " % of the bounding-box diagonal (parts removed or bridged: see the counts)");
  } catch (const InputError& e) {
    report.notes.push_back(std::string("input/output distances not measured: ") + e.what());
  }
  report.add("seconds_distances", step.seconds(), "s");
}

// The verdict: "closed" only for a watertight output, otherwise a warning naming what remains.
void addVerdict(StageReport& report, const MeshMetrics& after, const std::string& output_kind) {
  if (isWatertight(after)) {
    report.notes.push_back("result: closed, 2-manifold, free of self-intersections and degenerate faces (" +
                           output_kind + ")");
    return;
  }
  report.warnings.push_back("the result is NOT closed: " + watertightDefects(after) + " (" + output_kind + ")");
}

}  // namespace

bool isWatertight(const MeshMetrics& m) {
  return m.faces > 0 && m.closed && m.boundary_edges == 0 && m.non_manifold_edges == 0 &&
         m.non_manifold_vertices == 0 && m.self_intersecting_pairs == 0 && m.degenerate_faces == 0;
}

std::string watertightDefects(const MeshMetrics& m) {
  std::string out;
  const auto add = [&out](std::int64_t n, const char* what) {
    if (n > 0) out += (out.empty() ? "" : ", ") + std::to_string(n) + " " + what;
  };
  if (m.faces == 0) return "no face";
  add(m.boundary_loops, "boundary loops");
  if (m.boundary_loops == 0) add(m.boundary_edges, "boundary edges");
  add(m.non_manifold_edges, "non-manifold edges");
  add(m.non_manifold_vertices, "non-manifold vertices");
  add(m.self_intersecting_pairs, "self-intersecting face pairs");
  add(m.degenerate_faces, "degenerate faces");
  return out;
}

TriangleMesh cleanMesh(const TriangleMesh& input, const MeshCleanupOptions& options, StageReport& report,
                       const std::filesystem::path& source) {
  report = StageReport{};
  report.name = "mesh clean";
  const Stopwatch total;
  checkMeshInput(input, source);
  if (input.faces.empty()) {
    report.skipped = true;
    report.skip_reason = "the mesh has no face: nothing to repair or close";
    report.add("before_vertices", static_cast<std::int64_t>(input.vertices.size())).add("before_faces", std::int64_t{0});
    report.seconds = total.seconds();
    return input;
  }

  Stopwatch step;
  const MeshMetrics before = evaluateMesh(input);
  addMeshCounts(report, "before_", before);
  report.add("seconds_evaluation_before", step.seconds(), "s");

  step = Stopwatch();
  SoupRepair repair;
  SurfaceMesh mesh = repairSoup(input, &repair);
  addSoupRepairCounts(report, repair);
  report.add("seconds_repair", step.seconds(), "s");
  if (mesh.n_faces() == 0)
    throw InputError(source, "none of the " + std::to_string(input.faces.size()) +
                                 " faces has an area (all repeated-corner, collinear or duplicate): no surface to repair");

  step = Stopwatch();
  fillMeshHoles(report, mesh, options);
  report.add("seconds_hole_filling", step.seconds(), "s");

  TriangleMesh output = toTriangleMesh(mesh);
  std::string output_kind = "repaired";
  bool wrapped = false;
  if (options.wrap) {
    wrapped = wrapStep(report, output, options);
    output_kind = wrapped ? "alpha wrap, as asked" : "repaired: the wrap asked for did not finish";
  }
  if (!wrapped && options.repair_intersections) repairIntersectionsStep(report, output, options);
  else if (!wrapped) report.notes.push_back("self-intersection repair off");

  step = Stopwatch();
  MeshMetrics after = evaluateMesh(output);
  double evaluation_seconds = step.seconds();
  if (!wrapped && !options.wrap && !isWatertight(after) && options.wrap_fallback && options.fill_holes) {
    const std::string defects = watertightDefects(after);
    if (wrapStep(report, output, options)) {
      wrapped = true;
      output_kind = "alpha wrap, because the repaired mesh had " + defects;
      report.warnings.push_back("repair left " + defects + ": the output is the alpha wrap of the repaired mesh");
      step = Stopwatch();
      after = evaluateMesh(output);
      evaluation_seconds += step.seconds();
    }
  }
  report.add("wrapped", wrapped);
  addMeshCounts(report, "after_", after);
  report.add("seconds_evaluation_after", evaluation_seconds, "s");
  addSurfaceDistances(report, input, output, options);
  addVerdict(report, after, output_kind);
  report.seconds = total.seconds();
  return output;
}

}  // namespace solo
