// afford's version: the project's and the git commit it was built from
// ("0.1.0+655a8cb", "-dirty" when built with uncommitted changes). Generated
// into one source file at configure time (common/src/version.cpp.in), so a
// new commit recompiles that file alone.
#pragma once

namespace afford {

const char* affordVersion();

}  // namespace afford
