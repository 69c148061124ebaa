# LCM 1.3.1 built from source with the project's patches (third_party/lcm/README.md).
#
# afford_bundled_lcm(TARGET): a static library TARGET of liblcm, from the tarball that
# scripts/fetch-lcm.sh keeps in third_party/lcm/dist/, extracted into the build tree and
# patched there with third_party/lcm/patches/*.patch in order. Its include directory
# gives <lcm/lcm-cpp.hpp>, <lcm/lcm_coretypes.h> and <lcm/eventlog.h>. A changed patch
# re-extracts and re-patches at the next build. The wire format is LCM's own: Debian's
# lcm-spy, lcm-logger and lcm-logplayer interoperate with it.
set(AFFORD_LCM_VERSION 1.3.1)
set(AFFORD_LCM_TARBALL_NAME lcm_1.3.1+repack1.orig.tar.gz)
set(AFFORD_LCM_TARBALL_SHA256 abf293e54aff3d073cb4f9d4d5a261eab0e5ffea02e13fd601715c11612b85e8)

# afford_apply_patches(SRC WHAT PATCH...): each patch applied in SRC in order (patch -p1); a patch that does not
# apply stops the configure, naming WHAT (also used by cmake/BundledHttplib.cmake).
function(afford_apply_patches src what)
  find_program(PATCH_EXECUTABLE patch REQUIRED)
  foreach(p ${ARGN})
    execute_process(COMMAND ${PATCH_EXECUTABLE} -p1 --forward --batch --silent -i ${p}
                    WORKING_DIRECTORY ${src} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
    if(NOT rc EQUAL 0)
      message(FATAL_ERROR "patch ${p} does not apply to ${what}:\n${out}")
    endif()
  endforeach()
endfunction()

# afford_checked_source(FILE SHA256 FETCH WHAT): stops the configure unless FILE (a source tarball that the
# script FETCH keeps) is there with that SHA-256, saying how to get it (also used by cmake/BundledHttplib.cmake).
function(afford_checked_source file sha256 fetch what)
  if(NOT EXISTS ${file})
    message(FATAL_ERROR "${file} is missing: run ${fetch} (scripts/setup.sh does) to fetch ${what}'s source, "
                        "which afford builds with its own patches")
  endif()
  file(SHA256 ${file} got)
  if(NOT got STREQUAL sha256)
    message(FATAL_ERROR "${file} has SHA-256 ${got}, not ${sha256}: remove it and run ${fetch} again")
  endif()
endfunction()

function(afford_bundled_lcm target)
  get_filename_component(root ${CMAKE_CURRENT_FUNCTION_LIST_DIR}/.. ABSOLUTE)
  set(tarball ${root}/third_party/lcm/dist/${AFFORD_LCM_TARBALL_NAME})
  afford_checked_source(${tarball} ${AFFORD_LCM_TARBALL_SHA256} scripts/fetch-lcm.sh "LCM ${AFFORD_LCM_VERSION}")
  set(got ${AFFORD_LCM_TARBALL_SHA256})
  file(GLOB patches ${root}/third_party/lcm/patches/*.patch)
  list(SORT patches)
  set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${tarball} ${patches})

  # Extract and patch again whenever the tarball or a patch changes.
  set(deps ${CMAKE_BINARY_DIR}/_deps)
  set(src ${deps}/lcm-${AFFORD_LCM_VERSION})
  set(stamp_text ${got})
  foreach(p ${patches})
    file(SHA256 ${p} h)
    string(APPEND stamp_text "\n${h}")
  endforeach()
  set(stamp ${deps}/lcm-${AFFORD_LCM_VERSION}.stamp)
  set(old_stamp "")
  if(EXISTS ${stamp})
    file(READ ${stamp} old_stamp)
  endif()
  if(NOT old_stamp STREQUAL stamp_text OR NOT EXISTS ${src}/lcm/lcm.c)
    file(REMOVE_RECURSE ${src} ${stamp})
    # TOUCH: the extracted files are new to make, so every object built from the earlier extraction is
    # built again (with the archive's dates, a file a removed patch had changed, or a header, kept its old
    # object: code built against another layout of LCM's structures, which crashed).
    file(ARCHIVE_EXTRACT INPUT ${tarball} DESTINATION ${deps} TOUCH)
    afford_apply_patches(${src} "LCM ${AFFORD_LCM_VERSION}" ${patches})
    file(WRITE ${stamp} "${stamp_text}")
    list(LENGTH patches n)
    message(STATUS "LCM ${AFFORD_LCM_VERSION}: extracted into ${src} and patched (${n} patches)")
  endif()

  find_package(PkgConfig REQUIRED)
  pkg_check_modules(AFFORD_GLIB REQUIRED IMPORTED_TARGET glib-2.0 gthread-2.0)
  find_package(Threads REQUIRED)
  add_library(${target} STATIC
    ${src}/lcm/lcm.c
    ${src}/lcm/lcm_udpm.c
    ${src}/lcm/lcm_mpudpm.c
    ${src}/lcm/lcm_file.c
    ${src}/lcm/lcm_memq.c
    ${src}/lcm/lcm_tcpq.c
    ${src}/lcm/ringbuffer.c
    ${src}/lcm/udpm_util.c
    ${src}/lcm/eventlog.c
    ${src}/lcm/lcmtypes/channel_to_port_t.c
    ${src}/lcm/lcmtypes/channel_port_map_update_t.c)
  set_target_properties(${target} PROPERTIES C_STANDARD 99 C_EXTENSIONS ON POSITION_INDEPENDENT_CODE ON)
  # Upstream's code, built as upstream builds it: its warnings are not ours to fix here.
  target_compile_options(${target} PRIVATE -w)
  target_compile_definitions(${target} PRIVATE GLIB_DISABLE_DEPRECATION_WARNINGS)
  target_include_directories(${target} PUBLIC ${src})
  target_link_libraries(${target} PUBLIC PkgConfig::AFFORD_GLIB Threads::Threads)
endfunction()
