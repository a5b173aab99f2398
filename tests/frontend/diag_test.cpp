// The diagnostics engine (frontend/diag.h, docs/diagnostics.md): the edit
// distance behind "did you mean", the -W options, the -fmax-errors stop, and
// notes that follow their warning.  The distances are the textbook values
// (kitten/sitting: 3 edits; an adjacent transposition counts 1 in
// Damerau-Levenshtein; "ca" -> "abc" is 3 in its optimal-string-alignment
// form, which edits no substring twice).
#include <gtest/gtest.h>

#include "frontend/diag.h"

using namespace ldc;

TEST(Diag, EditDistance) {
  EXPECT_EQ(edit_distance("kitten", "sitting"), 3u);
  EXPECT_EQ(edit_distance("strat", "start"), 1u);  // one transposition
  EXPECT_EQ(edit_distance("motr", "motor"), 1u);
  EXPECT_EQ(edit_distance("START", "start"), 0u);  // case is ignored
  EXPECT_EQ(edit_distance("", "abc"), 3u);
  EXPECT_EQ(edit_distance("ca", "abc"), 3u);
}

TEST(Diag, ClosestName) {
  std::vector<std::string> names = {"stop", "start", "motor"};
  EXPECT_EQ(closest_name("strat", names), "start");
  EXPECT_EQ(closest_name("Motor", names), "");  // the same name in another case is no suggestion
  EXPECT_EQ(closest_name("xyzzy", names), "");
  EXPECT_EQ(closest_name("ab", {"abc"}), "abc");     // short names: 1 edit
  EXPECT_EQ(closest_name("ab", {"xy"}), "");         // ... not 2
  EXPECT_EQ(closest_name("hat", {"cat", "bat"}), "cat");  // the first of equals
  EXPECT_EQ(closest_name("strtr", {"start", "strt"}), "strt");  // the nearest, not the first
  EXPECT_EQ(did_you_mean("strat", names), "; did you mean 'start'?");
}

TEST(Diag, Options) {
  DiagOptions o;
  EXPECT_TRUE(o.enabled("double-coil"));
  EXPECT_FALSE(o.enabled("unused"));
  EXPECT_EQ(o.parse("-Wall"), "");
  EXPECT_TRUE(o.enabled("unused"));
  EXPECT_EQ(o.parse("-Wno-double-coil"), "");
  EXPECT_FALSE(o.enabled("double-coil"));
  EXPECT_EQ(o.parse("-O2"), std::nullopt);
  EXPECT_EQ(o.parse("-Wdouble-coils"), "unknown warning option '-Wdouble-coils'; did you mean '-Wdouble-coil'?");
  // the suggestion keeps the option's own prefix
  EXPECT_EQ(o.parse("-Wno-doubl-coil"), "unknown warning option '-Wno-doubl-coil'; did you mean '-Wno-double-coil'?");
  EXPECT_EQ(o.parse("-Werror=shared-timers"), "unknown warning option '-Werror=shared-timers'; did you mean '-Werror=shared-timer'?");
  EXPECT_EQ(o.parse("-Werror=unused"), "");
  EXPECT_TRUE(o.is_error("unused"));
  EXPECT_FALSE(o.is_error("undriven"));
  EXPECT_EQ(o.parse("-fmax-errors=0"), "");
  EXPECT_EQ(o.max_errors, 0);
  EXPECT_NE(o.parse("-fmax-errors=-1"), "");
  EXPECT_EQ(o.parse("-w"), "");
  EXPECT_FALSE(o.enabled("unused"));
}

TEST(Diag, StopsOnePastTheLimit) {
  DiagOptions o;
  o.max_errors = 2;
  Diagnostics d(o);
  d.source("f.ld", "a\nb\nc\n");
  d.error("f.ld", 1, 1, "one");
  d.error("f.ld", 2, 1, "two");
  EXPECT_THROW(d.error("f.ld", 3, 1, "three"), ErrorsReported);
  EXPECT_EQ(d.errors(), 2);
  EXPECT_EQ(d.text(), "f.ld:1:1: error: one\na\n^\nf.ld:2:1: error: two\nb\n^\n"
                      "fatal error: too many errors emitted, stopping now [-fmax-errors=2]\n");
}

TEST(Diag, NotesFollowTheirWarning) {
  DiagOptions o;
  o.chosen["double-coil"] = false;
  Diagnostics d(o);
  d.source("f.ld", "  x\n");
  EXPECT_FALSE(d.warning("double-coil", "f.ld", 1, 3, "w"));
  d.note("f.ld", 1, 1, "dropped with its warning");
  EXPECT_TRUE(d.warning("undriven", "f.ld", 1, 3, "read"));
  d.note("f.ld", 1, 1, "kept");
  EXPECT_EQ(d.text(), "f.ld:1:3: warning: read [-Wundriven]\n  x\n  ^\nf.ld:1:1: note: kept\n  x\n^\n");
  EXPECT_EQ(d.warnings(), 1);
  EXPECT_EQ(d.errors(), 0);
}

TEST(Diag, WerrorCountsAnError) {
  DiagOptions o;
  o.werror = true;
  Diagnostics d(o);
  EXPECT_TRUE(d.warning("undriven", "f.ld", 1, 1, "read"));
  EXPECT_EQ(d.errors(), 1);
  EXPECT_EQ(d.text(), "f.ld:1:1: error: read [-Werror=undriven]\n");
  EXPECT_THROW(d.check(), ErrorsReported);
}
