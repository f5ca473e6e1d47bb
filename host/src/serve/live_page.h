// The live view's page (live_page.html, embedded at build time by CMakeLists.txt).
#pragma once

#include <string_view>

namespace crunch::serve {

// The whole HTML document, UTF-8.
std::string_view livePageHtml();

}  // namespace crunch::serve
