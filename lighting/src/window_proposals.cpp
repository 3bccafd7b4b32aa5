// Windows: dark rectangles on building facades, found in facade-rectified coordinates. The
// facades are vertical planes fitted to the building pixels' 3D points (sequential RANSAC of
// lines in the top view); each is resampled from the day image on a metric grid (along the
// facade x height above ground), so a window is an axis-aligned rectangle of its real size
// whatever the perspective. A cell darker than the facade's local median (a 3 m median filter)
// is glass; connected dark cells of a window's size and rectangular shape are windows. Windows
// of one facade are grouped into floors by height.

#include "light_proposal_steps.h"

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <random>

namespace solo::proposals {
namespace {

struct FacadePoint {
  int u, v;
  double x, f, h;  ///< lateral, along the street, height above ground
};

// A vertical facade plane: n . (x, f) = offset in the top view, t = (-n.y, n.x) along it.
struct Facade {
  Eigen::Vector2d normal{1, 0};
  double offset = 0;
  double s_min = 0, s_max = 0, top_m = 0;
  Eigen::Vector2d t() const { return {-normal.y(), normal.x()}; }
  Eigen::Vector2d origin() const { return normal * offset; }
  double distance(double x, double f) const { return std::abs(normal.dot(Eigen::Vector2d(x, f)) - offset); }
  double s(double x, double f) const { return t().dot(Eigen::Vector2d(x, f)); }
};

double tolerance(const FacadePoint& p) { return 0.25 + 0.008 * std::hypot(p.x, p.f); }

std::vector<FacadePoint> buildingPoints(const ProposalInputs& in) {
  std::vector<FacadePoint> points;
  const int step = std::max(1, static_cast<int>(std::sqrt(static_cast<double>(in.labels.total()) / 60000.0)));
  for (int v = 0; v < in.height(); v += step)
    for (int u = 0; u < in.width(); u += step) {
      if (in.labelAt(u, v) != kBuilding) continue;
      const float z = in.depthAt(u, v);
      if (!(z > 0)) continue;
      const Eigen::Vector3d p = in.point(u, v, z);
      points.push_back({u, v, in.lateral(p), in.along(p), in.ground.heightOf(p)});
    }
  return points;
}

// Least-squares line (PCA) through the points' top-view positions.
Facade lineThrough(const std::vector<const FacadePoint*>& points) {
  Eigen::Vector2d mean(0, 0);
  for (const FacadePoint* p : points) mean += Eigen::Vector2d(p->x, p->f);
  mean /= static_cast<double>(points.size());
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
  for (const FacadePoint* p : points) {
    const Eigen::Vector2d d = Eigen::Vector2d(p->x, p->f) - mean;
    scatter += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> solver(scatter);
  Facade facade;
  facade.normal = solver.eigenvectors().col(0);
  facade.offset = facade.normal.dot(mean);
  return facade;
}

// Sequential RANSAC: up to 6 facades, each holding at least 3 % of the building points.
std::vector<Facade> fitFacades(std::vector<FacadePoint> points) {
  std::vector<Facade> facades;
  std::mt19937 rng(4242);
  const std::size_t least = std::max<std::size_t>(200, points.size() * 3 / 100);
  while (facades.size() < 6 && points.size() >= least) {
    std::uniform_int_distribution<std::size_t> pick(0, points.size() - 1);
    Facade best;
    std::size_t best_count = 0;
    for (int iteration = 0; iteration < 150; ++iteration) {
      const FacadePoint& a = points[pick(rng)];
      const FacadePoint& b = points[pick(rng)];
      const Eigen::Vector2d d(b.x - a.x, b.f - a.f);
      if (d.norm() < 1.0) continue;
      Facade candidate;
      candidate.normal = Eigen::Vector2d(-d.y(), d.x()).normalized();
      candidate.offset = candidate.normal.dot(Eigen::Vector2d(a.x, a.f));
      std::size_t count = 0;
      for (const FacadePoint& p : points) count += candidate.distance(p.x, p.f) < tolerance(p);
      if (count > best_count) best_count = count, best = candidate;
    }
    if (best_count < least) break;
    std::vector<const FacadePoint*> inliers;
    for (const FacadePoint& p : points)
      if (best.distance(p.x, p.f) < tolerance(p)) inliers.push_back(&p);
    Facade facade = lineThrough(inliers);
    std::vector<double> s, h;
    for (const FacadePoint* p : inliers) s.push_back(facade.s(p->x, p->f)), h.push_back(p->h);
    facade.s_min = quantile(s, 0.005) - 1.0;
    facade.s_max = quantile(s, 0.995) + 1.0;
    facade.top_m = std::min(80.0, quantile(h, 0.995) + 0.5);
    facades.push_back(facade);
    std::vector<FacadePoint> rest;
    for (const FacadePoint& p : points)
      if (facade.distance(p.x, p.f) >= tolerance(p)) rest.push_back(p);
    points.swap(rest);
  }
  return facades;
}

// The facade resampled on a grid of `cell` metres: luminance 0-255 (CV_8U) and validity (CV_8U).
struct Rectified {
  cv::Mat luma, valid;
  double cell = 0.1;
};

// The image pixel showing facade point (s, h), or (-1, -1) when it is off the image, not
// building, or its depth says something else is in front.
cv::Point facadePixel(const ProposalInputs& in, const Facade& facade, double s, double h) {
  const Eigen::Vector2d xf = facade.origin() + facade.t() * s;
  const Eigen::Vector3d p = in.groundFramePoint(xf.x(), h, xf.y());
  if (p.z() < 0.3) return {-1, -1};
  const Eigen::Vector2d uv = in.camera.project(p);
  const int u = static_cast<int>(std::lround(uv.x())), v = static_cast<int>(std::lround(uv.y()));
  if (u < 0 || v < 0 || u >= in.width() || v >= in.height() || in.labelAt(u, v) != kBuilding) return {-1, -1};
  const float z = in.depthAt(u, v);
  if (z > 0 && std::abs(z - p.z()) > 0.3 + 0.08 * p.z()) return {-1, -1};
  return {u, v};
}

Rectified rectify(const ProposalInputs& in, const Facade& facade, double cell) {
  Rectified r;
  r.cell = cell;
  const int cols = static_cast<int>((facade.s_max - facade.s_min) / cell) + 1;
  const int rows = static_cast<int>(facade.top_m / cell) + 1;
  r.luma = cv::Mat::zeros(rows, cols, CV_8U);
  r.valid = cv::Mat::zeros(rows, cols, CV_8U);
  std::vector<double> values;
  for (int row = 0; row < rows; ++row)
    for (int col = 0; col < cols; ++col) {
      const cv::Point q = facadePixel(in, facade, facade.s_min + (col + 0.5) * cell, facade.top_m - (row + 0.5) * cell);
      if (q.x < 0) continue;
      const cv::Vec3f c = in.image.at<cv::Vec3f>(q);
      const double luma = std::clamp(255.0 * (0.299 * c[0] + 0.587 * c[1] + 0.114 * c[2]), 0.0, 255.0);
      r.luma.at<std::uint8_t>(row, col) = static_cast<std::uint8_t>(luma);
      r.valid.at<std::uint8_t>(row, col) = 255;
      values.push_back(luma);
    }
  // Cells off the facade take its median so that they pull the local median neither way.
  r.luma.setTo(cv::Scalar(quantile(values, 0.5)), r.valid == 0);
  return r;
}

struct WindowRect {
  double s0, s1, h0, h1;
  double contrast, fill;
};

std::vector<WindowRect> darkRectangles(const Rectified& r, const Facade& facade) {
  std::vector<WindowRect> windows;
  const double cell = r.cell;
  int k = static_cast<int>(3.0 / cell) | 1;
  k = std::min(k, 2 * (std::min(r.luma.rows, r.luma.cols) / 2) - 1);
  if (k < 3) return windows;
  cv::Mat reference;
  cv::medianBlur(r.luma, reference, k);
  cv::Mat dark = cv::Mat::zeros(r.luma.size(), CV_8U);
  for (int row = 0; row < dark.rows; ++row)
    for (int col = 0; col < dark.cols; ++col) {
      const double l = r.luma.at<std::uint8_t>(row, col), ref = reference.at<std::uint8_t>(row, col);
      dark.at<std::uint8_t>(row, col) = r.valid.at<std::uint8_t>(row, col) && l < 0.72 * ref && ref - l > 12 ? 255 : 0;
    }
  cv::morphologyEx(dark, dark, cv::MORPH_OPEN, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(3, 3)));
  cv::Mat ids, stats, centroids;
  const int n = cv::connectedComponentsWithStats(dark, ids, stats, centroids, 8, CV_32S);
  std::vector<double> contrast(static_cast<std::size_t>(n), 0.0);
  for (int row = 0; row < ids.rows; ++row)
    for (int col = 0; col < ids.cols; ++col)
      if (const int id = ids.at<int>(row, col); id > 0)
        contrast[static_cast<std::size_t>(id)] +=
            1.0 - r.luma.at<std::uint8_t>(row, col) / std::max(1.0, double(reference.at<std::uint8_t>(row, col)));
  for (int i = 1; i < n; ++i) {
    const int w = stats.at<int>(i, cv::CC_STAT_WIDTH), h = stats.at<int>(i, cv::CC_STAT_HEIGHT);
    const int area = stats.at<int>(i, cv::CC_STAT_AREA);
    const double w_m = w * cell, h_m = h * cell, fill = static_cast<double>(area) / (w * h);
    if (w_m < 0.5 || w_m > 4.0 || h_m < 0.6 || h_m > 3.5 || fill < 0.45) continue;
    WindowRect window;
    window.s0 = facade.s_min + stats.at<int>(i, cv::CC_STAT_LEFT) * cell;
    window.s1 = window.s0 + w_m;
    window.h1 = facade.top_m - stats.at<int>(i, cv::CC_STAT_TOP) * cell;
    window.h0 = window.h1 - h_m;
    if (window.h0 < 0.3) continue;
    window.contrast = contrast[static_cast<std::size_t>(i)] / area;
    window.fill = fill;
    windows.push_back(window);
  }
  return windows;
}

// Floor index of each window: sorted by centre height, a new floor wherever the centre rises
// more than 1.5 m above the floor's lowest window.
std::vector<int> floorsOf(const std::vector<WindowRect>& windows) {
  std::vector<std::size_t> order(windows.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  const auto centre = [&](std::size_t i) { return (windows[i].h0 + windows[i].h1) / 2; };
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return centre(a) < centre(b); });
  std::vector<int> floor(windows.size(), 0);
  int current = -1;
  double base = -1e9;
  for (std::size_t i : order) {
    if (centre(i) > base + 1.5) ++current, base = centre(i);
    floor[i] = current;
  }
  return floor;
}

// The image pixels of a window rectangle that show the facade.
std::vector<cv::Point> windowPixels(const ProposalInputs& in, const Facade& facade, const WindowRect& w,
                                    Eigen::Vector3d& centre) {
  std::vector<cv::Point2d> corners;
  for (const auto& [s, h] : {std::pair{w.s0, w.h0}, {w.s1, w.h0}, {w.s1, w.h1}, {w.s0, w.h1}}) {
    const Eigen::Vector2d xf = facade.origin() + facade.t() * s;
    const Eigen::Vector3d p = in.groundFramePoint(xf.x(), h, xf.y());
    if (p.z() < 0.3) return {};
    const Eigen::Vector2d uv = in.camera.project(p);
    corners.emplace_back(uv.x(), uv.y());
  }
  const Eigen::Vector2d mid = facade.origin() + facade.t() * ((w.s0 + w.s1) / 2);
  centre = in.groundFramePoint(mid.x(), (w.h0 + w.h1) / 2, mid.y());
  std::vector<cv::Point> pixels;
  for (const cv::Point& p : convexPolygonPixels(corners, in.labels.size())) {
    if (in.labelAt(p.x, p.y) != kBuilding) continue;
    const float z = in.depthAt(p.x, p.y);
    const Eigen::Vector3d r = in.ray(p.x, p.y);
    const double plane_z = facade.offset / facade.normal.dot(Eigen::Vector2d(in.lateral(r), in.along(r)));
    if (z > 0 && plane_z > 0 && std::abs(z - plane_z) > 0.5 + 0.15 * plane_z) continue;
    pixels.push_back(p);
  }
  return pixels;
}

}  // namespace

void proposeWindows(const ProposalInputs& in, const LightProposalOptions& options, std::vector<DraftLight>& out,
                    StageReport& report) {
  const std::vector<Facade> facades = fitFacades(buildingPoints(in));
  int proposed = 0;
  for (std::size_t f = 0; f < facades.size(); ++f) {
    const Facade& facade = facades[f];
    double cell = options.facade_cell_m;
    while ((facade.s_max - facade.s_min) * facade.top_m / (cell * cell) > 3e6) cell *= 1.5;
    const Rectified rectified = rectify(in, facade, cell);
    const std::vector<WindowRect> windows = darkRectangles(rectified, facade);
    const std::vector<int> floors = floorsOf(windows);
    for (std::size_t i = 0; i < windows.size(); ++i) {
      DraftLight light;
      light.pixels = windowPixels(in, facade, windows[i], light.position_m);
      if (light.pixels.empty()) continue;
      light.category = LightCategory::WindowBuilding;
      light.height_m = (windows[i].h0 + windows[i].h1) / 2;
      light.score = std::clamp(windows[i].contrast * windows[i].fill * 2, 0.0, 1.0);
      light.rule = "dark_rectangle_on_facade";
      light.evidence = "facade " + std::to_string(f) + ": " + fixed(windows[i].s1 - windows[i].s0) + " x " +
                       fixed(windows[i].h1 - windows[i].h0) + " m at " + fixed(windows[i].h0) +
                       " m above ground, contrast " + fixed(windows[i].contrast) + ", fill " + fixed(windows[i].fill) +
                       ", floor " + std::to_string(floors[i] + 1);
      light.group_key = static_cast<long>(f) * 1000 + floors[i] + 1;
      light.source_instance = kBuilding;
      out.push_back(std::move(light));
      ++proposed;
    }
  }
  report.add("facades", static_cast<std::int64_t>(facades.size())).add("windows_proposed", static_cast<std::int64_t>(proposed));
}

}  // namespace solo::proposals
