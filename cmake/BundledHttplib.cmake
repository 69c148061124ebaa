# cpp-httplib 0.11.4 (header-only) from Debian's source package, with Debian's
# patches and the project's (third_party/httplib/README.md).
#
# afford_bundled_httplib(TARGET): an INTERFACE target TARGET whose include
# directory gives <httplib.h>: the two tarballs that scripts/fetch-httplib.sh
# keeps in third_party/httplib/dist/, extracted into the build tree, patched
# with Debian's debian/patches/series and then third_party/httplib/patches/*.patch
# in order. A changed patch re-extracts and re-patches at the next configure.
set(AFFORD_HTTPLIB_VERSION 0.11.4)
set(AFFORD_HTTPLIB_ORIG cpp-httplib_0.11.4+ds.orig.tar.xz)
set(AFFORD_HTTPLIB_ORIG_SHA256 8b1a5df569003b6a4f24c68489bbda5c64aec94697bdc9ebba5d79408b2ae7eb)
set(AFFORD_HTTPLIB_DEBIAN cpp-httplib_0.11.4+ds-1+deb12u1.debian.tar.xz)
set(AFFORD_HTTPLIB_DEBIAN_SHA256 a0adf8a38610806f6d94ba69839438635e5e6580775e28ff31d6a081e34f1484)

function(afford_bundled_httplib target)
  get_filename_component(root ${CMAKE_CURRENT_FUNCTION_LIST_DIR}/.. ABSOLUTE)
  set(dist ${root}/third_party/httplib/dist)
  foreach(part ORIG DEBIAN)
    afford_checked_source(${dist}/${AFFORD_HTTPLIB_${part}} ${AFFORD_HTTPLIB_${part}_SHA256} scripts/fetch-httplib.sh
                          "cpp-httplib ${AFFORD_HTTPLIB_VERSION}")
  endforeach()
  file(GLOB patches ${root}/third_party/httplib/patches/*.patch)
  list(SORT patches)
  set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${patches})

  set(deps ${CMAKE_BINARY_DIR}/_deps)
  set(src ${deps}/httplib-${AFFORD_HTTPLIB_VERSION})
  set(stamp_text "${AFFORD_HTTPLIB_ORIG_SHA256}\n${AFFORD_HTTPLIB_DEBIAN_SHA256}")
  foreach(p ${patches})
    file(SHA256 ${p} h)
    string(APPEND stamp_text "\n${h}")
  endforeach()
  set(stamp ${src}.stamp)
  set(old_stamp "")
  if(EXISTS ${stamp})
    file(READ ${stamp} old_stamp)
  endif()
  if(NOT old_stamp STREQUAL stamp_text OR NOT EXISTS ${src}/httplib.h)
    file(REMOVE_RECURSE ${src} ${stamp} ${deps}/httplib-extract)
    file(ARCHIVE_EXTRACT INPUT ${dist}/${AFFORD_HTTPLIB_ORIG} DESTINATION ${deps}/httplib-extract TOUCH)
    file(GLOB top ${deps}/httplib-extract/*)  # the tarball's one folder (yhirose-cpp-httplib-<commit>)
    file(RENAME ${top} ${src})
    file(REMOVE_RECURSE ${deps}/httplib-extract)
    file(ARCHIVE_EXTRACT INPUT ${dist}/${AFFORD_HTTPLIB_DEBIAN} DESTINATION ${src} TOUCH)
    file(STRINGS ${src}/debian/patches/series series REGEX "^[^#]")
    set(all)
    foreach(p ${series})
      list(APPEND all ${src}/debian/patches/${p})
    endforeach()
    list(APPEND all ${patches})
    afford_apply_patches(${src} "cpp-httplib ${AFFORD_HTTPLIB_VERSION}" ${all})
    file(WRITE ${stamp} "${stamp_text}")
    list(LENGTH all n)
    message(STATUS "cpp-httplib ${AFFORD_HTTPLIB_VERSION}: extracted into ${src} and patched (${n} patches)")
  endif()
  find_package(Threads REQUIRED)
  add_library(${target} INTERFACE)
  # As a system header: upstream's warnings are not ours to fix here.
  target_include_directories(${target} SYSTEM INTERFACE ${src})
  target_link_libraries(${target} INTERFACE Threads::Threads)
  # poll(), not select(): a request on a socket numbered past FD_SETSIZE (1024) is served, not answered 500.
  # (The page's server listens and accepts itself, experiment/watch/connections.hpp: httplib's listen
  # backlog, accept loop and thread pool are not used.)
  target_compile_definitions(${target} INTERFACE CPPHTTPLIB_USE_POLL)
endfunction()
