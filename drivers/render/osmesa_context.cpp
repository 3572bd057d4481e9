// GlContext on OSMesa: the only file that talks to OSMesa.
#include <GL/osmesa.h>

#include <cstdint>
#include <thread>

#include "drivers/render/gl_context.hpp"

namespace visvol::render {

namespace {
// The context's own buffer is never drawn into (frames go to framebuffer
// objects); it only has to exist, always at this one size.
constexpr int kBufferSidePx = 4;
}  // namespace

struct GlContext::Impl {
  OSMesaContext context = nullptr;
  std::uint32_t buffer[kBufferSidePx * kBufferSidePx] = {};
  std::thread::id bound_on;  // the thread it was last made current on
};

Result<std::unique_ptr<GlContext>> GlContext::create() {
  const int attributes[] = {OSMESA_FORMAT,
                            OSMESA_RGBA,
                            OSMESA_DEPTH_BITS,
                            0,
                            OSMESA_STENCIL_BITS,
                            0,
                            OSMESA_ACCUM_BITS,
                            0,
                            OSMESA_PROFILE,
                            OSMESA_CORE_PROFILE,
                            OSMESA_CONTEXT_MAJOR_VERSION,
                            3,
                            OSMESA_CONTEXT_MINOR_VERSION,
                            3,
                            0};
  std::unique_ptr<GlContext> c(new GlContext());
  c->impl_ = std::make_unique<Impl>();
  c->impl_->context = OSMesaCreateContextAttribs(attributes, nullptr);
  if (c->impl_->context == nullptr) {
    return Status(Errc::unsupported, "OSMesa: no OpenGL 3.3 core context (OSMesaCreateContextAttribs failed)");
  }
  VISVOL_RETURN_IF_ERROR(c->make_current());
  const auto text = [](GLenum name) {
    const GLubyte* s = glGetString(name);
    return s ? std::string(reinterpret_cast<const char*>(s)) : std::string("?");
  };
  c->renderer_ = text(GL_RENDERER);
  c->version_ = text(GL_VERSION);
  return c;
}

GlContext::~GlContext() {
  if (!impl_ || impl_->context == nullptr) return;
  if (OSMesaGetCurrentContext() == impl_->context) OSMesaMakeCurrent(nullptr, nullptr, 0, 0, 0);
  OSMesaDestroyContext(impl_->context);
}

Status GlContext::make_current() {
  // bound here already, and not since on another thread: nothing to do
  const std::thread::id self = std::this_thread::get_id();
  if (impl_->bound_on == self && OSMesaGetCurrentContext() == impl_->context) return Status::ok_status();
  // always the same buffer at the same size: Mesa reuses its framebuffer
  if (!OSMesaMakeCurrent(impl_->context, impl_->buffer, GL_UNSIGNED_BYTE, kBufferSidePx, kBufferSidePx)) {
    return Status(Errc::unsupported, "OSMesa: OSMesaMakeCurrent failed");
  }
  impl_->bound_on = self;
  return Status::ok_status();
}

}  // namespace visvol::render
