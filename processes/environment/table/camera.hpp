// The table world's camera: MuJoCo's renderer drawing the fixed top camera offscreen, in an OpenGL
// context that EGL gives without a display (Mesa's surfaceless platform; llvmpipe on a machine without a
// GPU). The same build, spec and state give the same image, byte for byte.
#pragma once
#include <mujoco/mujoco.h>
#include <opencv2/core.hpp>

#include <memory>
#include <thread>

#include "environment/table/physics.hpp"

namespace afford::table {

// One OpenGL context of this process, current on the thread that made it. Throws std::runtime_error
// naming the EGL step that failed (and the packages that give it) when there is none to be had.
class GlContext {
 public:
  GlContext();
  ~GlContext();
  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;
  // Makes one for the calling thread unless it has one (kept until the thread ends).
  static void onThisThread();

 private:
  void* display_ = nullptr;
  void* context_ = nullptr;
};

// What a camera shows: the agent's (the fixed top camera, the hand left out: its blobs are the objects, each
// pixel of an object its colour under the model's flat light), or a person's (the hand drawn too, the shapes
// shaded by a light from above; from the top camera, or from the side of the table looking down at it).
struct CameraView {
  bool hand = false;
  bool oblique = false;
};

class TableCamera {
 public:
  // Needs a GlContext current on this thread, for as long as the camera is used: it draws on this thread alone
  // (another thread's draw throws std::logic_error saying so).
  explicit TableCamera(const TablePhysics& physics, CameraView view = {});
  ~TableCamera();
  TableCamera(const TableCamera&) = delete;
  TableCamera& operator=(const TableCamera&) = delete;

  int width() const { return width_; }
  int height() const { return height_; }
  // The camera image of the simulation as it is: 8-bit RGB, row 0 at the top.
  cv::Mat rgb(const TablePhysics& physics);
  // Which object each pixel shows: its index in the spec's objects, or -1 (table, floor, hand). 32-bit ints.
  cv::Mat objects(const TablePhysics& physics);

  // The point of the table's top (z = 0) a pixel (column u, row v; centres at .5) shows, and the pixel a
  // point at height z shows: the camera looks straight down from `above` with `fovy_deg`.
  cv::Point2d tableAt(double u, double v) const;
  cv::Point2d pixelOf(double x, double y, double z = 0) const;

 private:
  void draw(const TablePhysics& physics, bool segments, unsigned char* out);

  int width_ = 0, height_ = 0;
  std::thread::id owner_;  // the thread whose OpenGL context holds this camera's buffers
  bool shaded_ = false;    // a person's view: the shapes shaded by a light from above
  CameraSpec spec_;  // its pinhole (afford/table_world.hpp)
  std::unique_ptr<mjvScene> scene_;
  std::unique_ptr<mjvCamera> camera_;
  std::unique_ptr<mjvOption> option_;
  std::unique_ptr<mjrContext> context_;
};

}  // namespace afford::table
