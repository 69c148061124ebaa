#include "environment/table/camera.hpp"

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace afford::table {

namespace {

std::string eglFailure(const std::string& step) {
  char code[16];
  std::snprintf(code, sizeof code, "0x%04x", static_cast<unsigned>(eglGetError()));
  return "the table's camera needs an OpenGL context from EGL without a display, and " + step + " failed (EGL " +
         code + "); Mesa gives one (Debian: libegl1, libegl-mesa0, libgl1-mesa-dri; scripts/setup.sh installs them)";
}

}  // namespace

GlContext::GlContext() {
  auto platformDisplay =
      reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (!platformDisplay) throw std::runtime_error(eglFailure("eglGetPlatformDisplayEXT"));
  EGLDisplay display = platformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  if (display == EGL_NO_DISPLAY) throw std::runtime_error(eglFailure("the surfaceless display"));
  EGLint major = 0, minor = 0;
  if (!eglInitialize(display, &major, &minor)) throw std::runtime_error(eglFailure("eglInitialize"));
  const EGLint attributes[] = {EGL_RED_SIZE,   8, EGL_GREEN_SIZE,      8, EGL_BLUE_SIZE,       8,
                               EGL_ALPHA_SIZE, 8, EGL_DEPTH_SIZE,     24, EGL_STENCIL_SIZE,    8,
                               EGL_COLOR_BUFFER_TYPE, EGL_RGB_BUFFER, EGL_SURFACE_TYPE, EGL_PBUFFER_BIT,
                               EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
  EGLConfig config = nullptr;
  EGLint found = 0;
  if (!eglChooseConfig(display, attributes, &config, 1, &found) || found < 1) {
    throw std::runtime_error(eglFailure("a configuration of 8-bit RGBA with depth and stencil"));
  }
  if (!eglBindAPI(EGL_OPENGL_API)) throw std::runtime_error(eglFailure("binding desktop OpenGL"));
  EGLContext context = eglCreateContext(display, config, EGL_NO_CONTEXT, nullptr);
  if (context == EGL_NO_CONTEXT) throw std::runtime_error(eglFailure("eglCreateContext"));
  if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context)) {
    eglDestroyContext(display, context);
    throw std::runtime_error(eglFailure("making the context current without a surface"));
  }
  display_ = display;
  context_ = context;
}

GlContext::~GlContext() {
  // The display is one for the whole process, other threads' contexts on it: it is never terminated.
  eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglDestroyContext(display_, context_);
}

void GlContext::onThisThread() {
  thread_local std::unique_ptr<GlContext> context;
  if (!context) context = std::make_unique<GlContext>();
}

TableCamera::TableCamera(const TablePhysics& physics, CameraView view)
    : width_(physics.spec().camera.width),
      height_(physics.spec().camera.height),
      owner_(std::this_thread::get_id()),
      shaded_(view.hand),
      spec_(physics.spec().camera),
      scene_(std::make_unique<mjvScene>()),
      camera_(std::make_unique<mjvCamera>()),
      option_(std::make_unique<mjvOption>()),
      context_(std::make_unique<mjrContext>()) {
  mjv_defaultScene(scene_.get());
  mjv_defaultCamera(camera_.get());
  mjv_defaultOption(option_.get());
  option_->geomgroup[kHandGroup] = view.hand ? 1 : 0;  // the hand is not in the agent's image: its blobs are the objects
  mjr_defaultContext(context_.get());
  mjv_makeScene(physics.model(), scene_.get(), 1000);
  mjr_makeContext(physics.model(), context_.get(), mjFONTSCALE_100);
  if (!context_->offFBO) {
    mjr_freeContext(context_.get());
    mjv_freeScene(scene_.get());
    throw std::runtime_error("MuJoCo's renderer made no offscreen buffer for the table's camera");
  }
  mjr_setBuffer(mjFB_OFFSCREEN, context_.get());
  camera_->type = mjCAMERA_FIXED;
  camera_->fixedcamid = mj_name2id(physics.model(), mjOBJ_CAMERA, "top");
  if (view.oblique) {  // from beyond the table's near long side, looking down at its centre
    const TableSpec& t = physics.spec();
    camera_->type = mjCAMERA_FREE;
    camera_->lookat[0] = camera_->lookat[1] = camera_->lookat[2] = 0;
    camera_->distance = 0.8 * std::max(t.half_x, t.half_y) / std::tan(t.camera.fovy_deg * M_PI / 360.0);
    camera_->azimuth = 0;   // looking along +x, the table's long side (y) across the image
    camera_->elevation = -45;
  }
  // What a plain camera sees: no reflections, shadows or sky.
  scene_->flags[mjRND_SHADOW] = 0;
  scene_->flags[mjRND_REFLECTION] = 0;
  scene_->flags[mjRND_SKYBOX] = 0;
}

TableCamera::~TableCamera() {
  mjr_freeContext(context_.get());
  mjv_freeScene(scene_.get());
}

void TableCamera::draw(const TablePhysics& physics, bool segments, unsigned char* out) {
  if (std::this_thread::get_id() != owner_)
    throw std::logic_error("the table's camera draws on the thread that made it alone (its OpenGL context is that "
                           "thread's): make the world on the thread that uses it");
  scene_->flags[mjRND_SEGMENT] = segments;
  scene_->flags[mjRND_IDCOLOR] = segments;
  mjv_updateScene(physics.model(), const_cast<mjData*>(physics.data()), option_.get(), nullptr, camera_.get(),
                  mjCAT_ALL, scene_.get());
  if (shaded_)  // a person's view: the model's flat light turned into a light from above that shades the shapes
    for (int i = 0; i < scene_->nlight; ++i) {
      for (int k = 0; k < 3; ++k) scene_->lights[i].ambient[k] *= 0.35f, scene_->lights[i].diffuse[k] = 0.75f;
    }
  const mjrRect viewport = {0, 0, width_, height_};
  mjr_setBuffer(mjFB_OFFSCREEN, context_.get());  // this camera's buffer: another camera may have bound its own
  mjr_render(viewport, scene_.get(), context_.get());
  mjr_readPixels(out, nullptr, viewport, context_.get());
}

cv::Mat TableCamera::rgb(const TablePhysics& physics) {
  cv::Mat up(height_, width_, CV_8UC3);
  draw(physics, false, up.data);
  cv::Mat image;
  cv::flip(up, image, 0);  // OpenGL's rows run bottom up
  return image;
}

cv::Mat TableCamera::objects(const TablePhysics& physics) {
  std::vector<unsigned char> ids(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_) * 3);
  draw(physics, true, ids.data());
  // The renderer paints each geom of the scene with its segmentation id + 1 (0: nothing drawn).
  std::vector<int> object_of_segment;
  for (int g = 0; g < scene_->ngeom; ++g) {
    const mjvGeom& geom = scene_->geoms[g];
    if (geom.segid < 0) continue;
    if (static_cast<std::size_t>(geom.segid) >= object_of_segment.size())
      object_of_segment.resize(static_cast<std::size_t>(geom.segid) + 1, -1);
    if (geom.objtype == mjOBJ_GEOM) object_of_segment[static_cast<std::size_t>(geom.segid)] = physics.objectOfGeom(geom.objid);
  }
  cv::Mat out(height_, width_, CV_32S);
  for (int v = 0; v < height_; ++v) {
    const unsigned char* row = ids.data() + static_cast<std::size_t>(height_ - 1 - v) * static_cast<std::size_t>(width_) * 3;
    for (int u = 0; u < width_; ++u) {
      const unsigned char* px = row + 3 * u;
      const int segment = px[0] + 256 * px[1] + 65536 * px[2] - 1;
      out.at<int>(v, u) = segment >= 0 && static_cast<std::size_t>(segment) < object_of_segment.size()
                              ? object_of_segment[static_cast<std::size_t>(segment)]
                              : -1;
    }
  }
  return out;
}

cv::Point2d TableCamera::tableAt(double u, double v) const {
  const auto [x, y] = spec_.tableAtPixel(u, v);
  return {x, y};
}

cv::Point2d TableCamera::pixelOf(double x, double y, double z) const {
  const auto [u, v] = spec_.pixelOf(x, y, z);
  return {u, v};
}

}  // namespace afford::table
