// An offscreen OpenGL 3.3 core context with no window.
//
// Today it is OSMesa (Mesa's gallium llvmpipe on the CPU; Debian
// libosmesa6-dev), and osmesa_context.cpp is the only file that knows. Mesa
// 25.1 removed OSMesa: a headless EGL context (EGL_MESA_platform_surfaceless,
// which matches the OSMesa image here) is another implementation of these
// three calls. Nothing is drawn into the context's own buffer: the renderer
// draws into framebuffer objects of its own, so the swap needs no other change.
//
// The context's buffer is bound once, at one fixed size, and re-bound only at
// that size (Mesa 22.3 leaks the old buffers when a context is re-bound at
// another size).
//
// Thread-safety: current on one thread at a time. make_current() binds it to
// the calling thread (a no-op when it already is current there); callers must
// not use one context from two threads at once. Not real-time safe.
#pragma once

#include <memory>
#include <string>

#include "base/status.hpp"

namespace visvol::render {

class GlContext {
 public:
  // Creates an OpenGL 3.3 (or later) core context and makes it current on
  // the calling thread. Fails with the reason when the driver has none.
  static Result<std::unique_ptr<GlContext>> create();
  ~GlContext();  // unbinds it if current on this thread; frees every GL object it holds
  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;

  // Binds the context on the calling thread (cheap when already current).
  Status make_current();

  // "llvmpipe (LLVM 15.0.6, 256 bits)", "4.5 (Core Profile) Mesa 22.3.6".
  const std::string& renderer() const { return renderer_; }
  const std::string& version() const { return version_; }

  struct Impl;

 private:
  GlContext() = default;
  std::unique_ptr<Impl> impl_;
  std::string renderer_, version_;
};

}  // namespace visvol::render
