# Writes OUT, the dashboard's browser libraries from npm as C++ strings (dashboard_vendor.hpp),
# at build time after `npm ci` put them under VENDOR (uPlot's dist/). Without VENDOR (configured
# with -DUSV_FDI_DASHBOARD_CHARTS=OFF) the strings are empty and kHaveCharts is false.
set(js "")
set(css "")
set(have false)
if(DEFINED VENDOR AND NOT VENDOR STREQUAL "")
  foreach(f uPlot.iife.min.js uPlot.min.css)
    if(NOT EXISTS ${VENDOR}/${f})
      message(FATAL_ERROR "${VENDOR}/${f} is missing: did `npm ci` install uplot?")
    endif()
  endforeach()
  file(READ ${VENDOR}/uPlot.iife.min.js js)
  file(READ ${VENDOR}/uPlot.min.css css)
  set(have true)
  if(js MATCHES "\\)usvfdivendor" OR css MATCHES "\\)usvfdivendor")
    message(FATAL_ERROR "uPlot contains the raw string's delimiter )usvfdivendor")
  endif()
endif()
file(WRITE ${OUT}.tmp
"// Generated at build time by src/app/dashboard/embed_vendor.cmake from the npm packages pinned in
// src/app/dashboard/web/package-lock.json: served from the binary, nothing fetched at run time.
#pragma once

namespace usvfdi::app::dashboard::vendor {

inline constexpr bool kHaveCharts = ${have};
inline constexpr const char* kUplotJs = R\"usvfdivendor(${js})usvfdivendor\";
inline constexpr const char* kUplotCss = R\"usvfdivendor(${css})usvfdivendor\";

}  // namespace usvfdi::app::dashboard::vendor
")
execute_process(COMMAND ${CMAKE_COMMAND} -E copy_if_different ${OUT}.tmp ${OUT})
file(REMOVE ${OUT}.tmp)
