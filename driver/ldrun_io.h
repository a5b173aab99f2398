// driver/ldrun_io.h -- what ldrun's x86-64 and C40 paths share: an image
// holding only a program's binary IL (for the interpreters), the --watch list
// and the --trace file, each with ldrun's error messages.
#pragma once

#include <string>
#include <vector>

#include "frontend/diag.h"
#include "ir/ir.h"
#include "loader/loader.h"
#include "runtime/runtime.h"

namespace ldc {

// The layout, binary IL and aliases of `p`, the IL validated (UserError if not).
Image il_image(const Program& p);

// "Y0,D3,motor" -> probes, by device or alias (UserError naming the bad one).
std::vector<Probe> parse_watch(const std::string& watch, const std::vector<Alias>& aliases);

// The trace CSV at `path` (UserError with file:line:col on a bad one); a
// column that writes an output gets -Wtrace-output.
Trace load_trace(const std::string& path, const std::vector<Alias>& aliases);

// ldrun's warnings (docs/diagnostics.md): its -W options, as ldc's.
void set_ldrun_warnings(const DiagOptions& o);
// Warning `name` about an option (no place in a file): "ldrun: warning: ...
// [-Wname]" on stderr, or a UserError under -Werror.
void ldrun_option_warning(const char* name, const std::string& msg);

}  // namespace ldc
