# Writes OUT: a header with the text of IN as a raw string literal, named
# k<Name>Source after IN's base name (mathrom.c40s -> kMathRomSource,
# interp.c40s -> kInterpSource).
get_filename_component(_name ${IN} NAME_WE)
if(_name STREQUAL "mathrom")
  set(_var kMathRomSource)
else()
  set(_var kInterpSource)
endif()
file(READ ${IN} _text)
string(FIND "${_text}" ")c40s\"" _bad)
if(NOT _bad EQUAL -1)
  message(FATAL_ERROR "${IN} contains the raw string delimiter")
endif()
file(WRITE ${OUT}.tmp "// generated from ${IN} by embed_c40s.cmake\n#pragma once\ninline constexpr const char ${_var}[] = R\"c40s(${_text})c40s\";\n")
file(RENAME ${OUT}.tmp ${OUT})
