# Writes the version source (common/src/version.cpp.in -> OUT) with the checkout's commit as it is now: run at
# every build (CMakeLists.txt, target afford_version), so that a build after a commit, or with uncommitted
# changes, says so, not the commit CMake was configured at. The file is rewritten only when the text changes,
# so an unchanged checkout recompiles nothing.
#   cmake -D SOURCE_DIR=... -D PROJECT_VERSION=... -D OUT=... -P cmake/version.cmake
# The commit alone (no tag's name: a release's version is the project's), "-dirty" with uncommitted changes.
execute_process(COMMAND git describe --always --dirty --exclude *
                WORKING_DIRECTORY ${SOURCE_DIR} OUTPUT_VARIABLE AFFORD_GIT
                OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
if(NOT AFFORD_GIT)
  set(AFFORD_GIT unknown)
endif()
set(AFFORD_VERSION_TEXT "${PROJECT_VERSION}+${AFFORD_GIT}")
configure_file(${SOURCE_DIR}/common/src/version.cpp.in ${OUT} @ONLY)
