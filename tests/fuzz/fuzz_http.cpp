// Fuzz the monitor's HTTP request parser (runtime/net/http.h): parse_request on
// the bytes, then on what follows each complete request (pipelining), and
// the form decoder on queries and bodies.  Besides not crashing, a complete
// request must consume only bytes it was given, and must parse the same way
// when exactly its own bytes are given; and a prefix refused at once (a
// request line that cannot be HTTP) must be refused whole too.
#include <cstdlib>

#include "runtime/net/http.h"
#include "tests/fuzz/fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view buf = LDC_FUZZ_TEXT(data, size);
  ldc::http::Limits lim;
  // an Error for a prefix is an Error for the whole: refusing early refuses
  // nothing the full parse would have served
  if (ldc::http::parse_request(buf, lim).status != ldc::http::Parse::Status::Error)
    for (size_t cut = 1; cut < 4; cut++)
      if (ldc::http::parse_request(buf.substr(0, buf.size() * cut / 4), lim).status == ldc::http::Parse::Status::Error)
        std::abort();
  for (int k = 0; k < 8 && !buf.empty(); k++) {
    ldc::http::Parse p = ldc::http::parse_request(buf, lim);
    if (p.status != ldc::http::Parse::Status::Done) {
      if (p.status == ldc::http::Parse::Status::Error && (p.code < 400 || p.code > 599 || p.reason.empty())) std::abort();
      break;
    }
    if (p.consumed == 0 || p.consumed > buf.size() || p.req.body.size() > lim.max_body) std::abort();
    ldc::http::Parse again = ldc::http::parse_request(buf.substr(0, p.consumed), lim);
    if (again.status != ldc::http::Parse::Status::Done || again.consumed != p.consumed || again.req.body != p.req.body)
      std::abort();
    (void)ldc::http::form_value(p.req.query, "device");
    (void)ldc::http::form_value(p.req.body, "value");
    (void)ldc::http::percent_decode(p.req.path);
    (void)p.req.keep_alive();
    buf.remove_prefix(p.consumed);
  }
  return 0;
}
