// A tangible-video user: writes a three-frame image sequence (a black
// square that moves right), reads it through the installed video part and
// feels the square's left edge in each frame.
#include <hapticfield/video.hpp>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cstdio>
#include <string>

int main(int argc, char** argv) {
  namespace hf = hapticfield;
  if (argc != 2) return 2;
  const std::string dir = argv[1];
  for (int k = 0; k < 3; ++k) {
    cv::Mat frame(120, 160, CV_8UC3, cv::Scalar::all(255));
    cv::rectangle(frame, cv::Rect(40 + 20 * k, 40, 40, 40), cv::Scalar::all(0), cv::FILLED);
    if (!cv::imwrite(dir + "/frame_" + std::to_string(k) + ".png", frame)) return 1;
  }
  hf::VideoSource source(dir + "/frame_%d.png");
  hf::PrepareConfig prepare;
  prepare.tangible.size = 5;
  hf::VideoTimeline timeline(source, prepare, 0.0);  // no fade-in: each frame is felt from its own time
  int felt = 0;
  for (int k = 0; k < 3; ++k) {
    const double t = source.time_of(k);
    const glm::dvec2 on_edge = timeline.at(t, 40.0 + 20.0 * k, 60.0);  // the left edge of frame k's square
    std::printf("consumer_video: frame %d at %.3f s, force on the edge %.3f\n", k, t, on_edge.x);
    if (std::abs(on_edge.x) > 0.1) ++felt;
  }
  return felt == 3 ? 0 : 1;
}
