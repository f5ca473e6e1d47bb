// Cairo handles in unique_ptrs (STYLE.md item 4), shared by the map montage and the charts.
// Private to the render area. Cairo never returns null: a failed creation gives an "error
// object" whose status says why, so callers check cairo_surface_status / cairo_status.
#pragma once

#include <cairo.h>

#include <memory>

namespace crunch::render_detail {

struct SurfaceDeleter {
  void operator()(cairo_surface_t* s) const { cairo_surface_destroy(s); }
};
struct ContextDeleter {
  void operator()(cairo_t* cr) const { cairo_destroy(cr); }
};
using SurfacePtr = std::unique_ptr<cairo_surface_t, SurfaceDeleter>;
using ContextPtr = std::unique_ptr<cairo_t, ContextDeleter>;

}  // namespace crunch::render_detail
