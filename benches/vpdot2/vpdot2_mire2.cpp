// ViSP's vpDot2 on the mire-2 frames (ViSP's image dataset, Debian's visp-images-data): the
// peer of `vsinv.DotTracker` in benches/tracker_mire2.py (benchmark only, never a dependency).
// Usage: vpdot2_mire2 DIR CLICKS [REPEATS]
//   DIR: the mire-2 folder (image.0001.pgm .. image.0501.pgm)
//   CLICKS: "u,v;u,v;..." approximate pixels of the dots in the first image
// Prints the time per frame (all dots, the 500 frames after the first), the number of frames
// where a dot was lost, and the last centroids (u, v).
#include <visp3/blob/vpDot2.h>
#include <visp3/core/vpImage.h>
#include <visp3/core/vpImagePoint.h>
#include <visp3/io/vpImageIo.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

static std::vector<vpImagePoint> parse_clicks(const std::string &text) {
  std::vector<vpImagePoint> clicks;
  std::stringstream all(text);
  std::string one;
  while (std::getline(all, one, ';')) {
    double u = 0, v = 0;
    if (std::sscanf(one.c_str(), "%lf,%lf", &u, &v) == 2) clicks.emplace_back(v, u);  // (i, j) = (v, u)
  }
  return clicks;
}

int main(int argc, char **argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s DIR 'u,v;u,v;...' [REPEATS]\n", argv[0]);
    return 2;
  }
  const std::string dir = argv[1];
  const std::vector<vpImagePoint> clicks = parse_clicks(argv[2]);
  const int repeats = argc > 3 ? std::atoi(argv[3]) : 5;
  std::vector<vpImage<unsigned char>> frames;
  for (int k = 1;; ++k) {
    char name[64];
    std::snprintf(name, sizeof name, "/image.%04d.pgm", k);
    vpImage<unsigned char> image;
    try {
      vpImageIo::read(image, dir + name);
    } catch (...) {
      break;
    }
    frames.push_back(image);
  }
  if (frames.size() < 2 || clicks.empty()) {
    std::fprintf(stderr, "need frames under %s and clicks\n", dir.c_str());
    return 2;
  }
  double best = 1e300;
  int lost_frames = 0;
  std::vector<vpDot2> dots;
  for (int r = 0; r < repeats; ++r) {
    dots.assign(clicks.size(), vpDot2());
    for (size_t i = 0; i < clicks.size(); ++i) {
      dots[i].setGraphics(false);
      dots[i].initTracking(frames[0], clicks[i]);
    }
    lost_frames = 0;
    const auto t0 = std::chrono::steady_clock::now();
    for (size_t f = 1; f < frames.size(); ++f) {
      bool lost = false;
      for (auto &dot : dots) {
        try {
          dot.track(frames[f]);
        } catch (...) {
          lost = true;
        }
      }
      lost_frames += lost;
    }
    const double us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
    best = std::min(best, us / double(frames.size() - 1));
  }
  std::printf("vpDot2: %zu dots, %zu frames, %.2f us/frame (best of %d), frames with a lost dot: %d\n", dots.size(),
              frames.size() - 1, best, repeats, lost_frames);
  for (auto &dot : dots) std::printf("last %.3f %.3f\n", dot.getCog().get_u(), dot.getCog().get_v());
  return 0;
}
