// frontend/st/st.h -- IEC 61131-3 Structured Text (docs/st.md): the lexer and
// the translation of ST bodies into the typed IEC IL reader's tokens.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "frontend/iecil/iecil.h"

namespace ldc::st {

// Names, numbers, literals and %addresses as Words (a.b.c one Word, as the IL
// lexer has them); operators and punctuation as Punct.  No Eol tokens: ST is
// free-form.  Comments (* *) (nested), // and pragmas {...} are skipped.
// Ends with End.  Throws CompileError.
std::vector<iecil::Tok> lex(std::string_view s);

// The whole file: declarations passed on, every POU body's statements written
// as IEC IL instructions located at their ST source, read by the typed IL
// reader.  A CONFIGURATION of several program instances is written for one
// of them, `instance` (its index in the configuration); with -1 it must run
// one.  Throws CompileError.
std::vector<iecil::Tok> to_il_tokens(const std::vector<iecil::Tok>& st, int instance = -1);
// The same with error recovery: a statement refused is reported to `rec`
// and left out (the typed reader then reads what remains with `rec`).  The
// file's structure (its POUs, VAR blocks, CONFIGURATION) stops at its first
// error, thrown as above.
std::vector<iecil::Tok> to_il_tokens(const std::vector<iecil::Tok>& st, int instance, iecil::Recovery& rec);

// The file's CONFIGURATION: its tasks and program instances, as written
// (instances empty: none).
struct ConfigTask {
  std::string name, resource, interval, priority;  // interval, priority: literals as written ("" if not given)
  int line = 0, col = 0;
};
struct ConfigInstance {
  std::string name, task, program;  // task "" without WITH
  int line = 0, col = 0;
};
struct Configuration {
  std::string name;
  std::vector<std::string> globals;  // VAR_GLOBAL names, upper-case
  std::vector<ConfigTask> tasks;
  std::vector<ConfigInstance> instances;
};
Configuration configuration(const std::vector<iecil::Tok>& st);

}  // namespace ldc::st
