// backend-c/c_shared.h -- the C route's shared object: the generated C compiled
// by the system C compiler, for the runtime's shared-object engine.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "ir/ir.h"

namespace ldc {

// A failure to write the C or to compile it; the message is meant to be
// printed as it is ("error: the C compiler failed ...", with its output).
struct CBuildError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Writes `text` (C from generate_c or generate_sfc_c) to DIR/prog.c and compiles
// it with ${CC:-cc} -O2 -shared -fPIC -ffp-contract=off into DIR/prog.so, the
// compiler's output in DIR/cc.log; returns the path of prog.so.  `extra_flags`
// go after those (a test adds -fsanitize=undefined).
std::string build_c_text(const std::string& text, const std::string& dir,
                         const std::vector<std::string>& extra_flags = {});
// ... of generate_c(p, p.layout()).
std::string build_c_shared_object(const Program& p, const std::string& dir);

}  // namespace ldc
