// The view names and the Renderer's thin accessors; the set-up is in
// renderer_setup.cpp, the per-frame drawing in renderer_draw.cpp.
#include "drivers/render/renderer.hpp"

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include "drivers/render/renderer_impl.hpp"

namespace visvol::render {

const char* to_string(View view) {
  switch (view) {
    case View::top: return "top";
    case View::oblique: return "oblique";
    case View::volume: return "volume";
    case View::slice: return "slice";
  }
  return "?";
}

Result<View> parse_view(const std::string& text) {
  for (View v : {View::top, View::oblique, View::volume, View::slice}) {
    if (text == to_string(v)) return v;
  }
  return invalid_argument("view '" + text + "' is not one of top, oblique, volume, slice");
}

Renderer::~Renderer() = default;  // the context owns every GL object and frees them with itself

Image Renderer::image() const {
  Image im;
  im.rgba = impl_->pixels.data();
  im.width_px = impl_->width;
  im.height_px = impl_->height;
  im.stride_bytes = static_cast<std::size_t>(impl_->width) * 4;
  return im;
}

Result<std::size_t> Renderer::encode_png(std::uint8_t* out, std::size_t capacity_bytes) {
  if (impl_->width == 0) return Status(Errc::state, "encode_png: no frame rendered yet");
  const Image im = image();
  return impl_->png->encode(im.rgba, im.width_px, im.height_px, im.stride_bytes, out, capacity_bytes);
}

std::optional<PixelPoint> Renderer::project(double x_m, double y_m, double z_m) const {
  if (impl_->width == 0 || impl_->view == View::slice) return std::nullopt;
  return impl_->camera.project(impl_->frame.to_scene(x_m, y_m, z_m));
}

std::optional<PixelPoint> Renderer::slice_pixel(double distance_m, double z_m) const {
  if (impl_->width == 0 || impl_->view != View::slice) return std::nullopt;
  return impl_->slice_point(layout_.scene, distance_m, z_m);
}

}  // namespace visvol::render
