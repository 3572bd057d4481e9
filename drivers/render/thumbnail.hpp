// The console's renderer thread in two calls: the latest path sample (as the
// executive hands it to the DDS layer) in, a ThumbnailSample (a whole PNG) out.
//
//   PathPoint scratch[msg::kMaxPathVertices];
//   while (running) {
//     if (const msg::PathSample* p = latest_path.take()) {
//       if (render_thumbnail(renderer, *p, frame, scratch, thumbnail_slot.back()).ok())
//         thumbnail_slot.publish();
//     }
//     ...wait...
//   }
//
// No allocation on success (the renderer's frame path and PNG arena), so the
// thread's memory stays flat however long the console runs. Not real-time
// safe: a frame takes milliseconds to a few hundred (see README). Header-only;
// uses the plain structs of msg/samples.hpp, not the DDS library.
#pragma once

#include <cstddef>

#include "drivers/render/renderer.hpp"
#include "msg/samples.hpp"

namespace visvol::render {

// Copies a path sample's vertices (position and F_p) into `out`, which holds
// `capacity` points; returns how many. Real-time safe.
inline std::size_t path_points_of(const msg::PathSample& sample, PathPoint* out, std::size_t capacity) {
  std::size_t n = sample.vertex_count;
  if (n > msg::kMaxPathVertices) n = msg::kMaxPathVertices;
  if (n > capacity) n = capacity;
  for (std::size_t i = 0; i < n; ++i) {
    const msg::PathVertex& v = sample.vertices[i];
    out[i] = {v.position.x_m, v.position.y_m, v.position.z_m, v.visibility};
  }
  return n;
}

// Renders `sample` with the view, size and markers of `frame` (its path is
// replaced) and encodes the PNG into `out`, stamped with the path's stamp.
// `scratch` holds msg::kMaxPathVertices points. On failure `out` is not a
// valid thumbnail (do not publish it) and the status says why.
inline Status render_thumbnail(Renderer& renderer, const msg::PathSample& sample, Frame frame, PathPoint* scratch,
                               msg::ThumbnailSample& out) {
  frame.path = scratch;
  frame.path_size = path_points_of(sample, scratch, msg::kMaxPathVertices);
  VISVOL_RETURN_IF_ERROR(renderer.render(frame));
  Result<std::size_t> bytes = renderer.encode_png(out.png, sizeof out.png);
  if (!bytes.ok()) return bytes.status();
  out.stamp_ns = sample.stamp_ns;
  out.png_size_bytes = static_cast<std::uint32_t>(*bytes);
  return Status::ok_status();
}

static_assert(kDefaultMaxPathVertices == msg::kMaxPathVertices,
              "the renderer reserves for the longest path the console publishes");

}  // namespace visvol::render
