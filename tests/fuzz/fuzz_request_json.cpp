// SPDX-License-Identifier: GPL-3.0-or-later
// libFuzzer target: the request decoding for every RPC — the strict JSON reader (from_json,
// application/json_read.cpp) into the request message, then the request's checks and conversion
// into kernel inputs (prepare_patch, prepare_design, ...; to_mesh reads mesh files and examples).
// The first byte picks the RPC, the rest is the body. A body from_json accepts must also print
// (to_json) and read back to an equal message: the reader takes everything the writer writes. The
// computations themselves (patch, design, deployment) are not run: they are tested on valid inputs
// elsewhere and would make each input seconds long.
#include <google/protobuf/util/field_comparator.h>
#include <google/protobuf/util/message_differencer.h>

#include <string>

#include "fuzz_support.h"
#include "gridshell/application/convert_deployment.h"
#include "gridshell/application/files.h"
#include "gridshell/application/requests.h"
#include "gridshell/v1/requests.pb.h"

namespace {

using namespace gridshell;

/// The body read strictly into `request`: false (after checking the error) if it is refused.
/// An accepted request must survive to_json and from_json unchanged.
template <class Request>
bool parse(const std::string& body, Request& request) {
  try {
    from_json(body, request);
  } catch (const Error& e) {
    fuzz::expect_invalid_input(e);
    return false;
  }
  const std::string again = to_json(request, false);
  Request back;
  try {
    from_json(again, back);
  } catch (const Error& e) {
    fuzz::fail("from_json refuses to_json's text of a request it accepted: " +
               std::string(e.what()) + "\n" + again.substr(0, 400));
  }
  google::protobuf::util::DefaultFieldComparator comparator;
  comparator.set_treat_nan_as_equal(true);  // "NaN" reads back as a NaN
  google::protobuf::util::MessageDifferencer differencer;
  differencer.set_field_comparator(&comparator);
  if (!differencer.Compare(request, back))
    fuzz::fail("a request read by from_json does not read back from to_json's text:\n" +
               again.substr(0, 400));
  return true;
}

void check_design(const v1::DesignRequest& request) {
  DesignInputs inputs = prepare_design(request);
  fuzz::check_loaded(inputs.mesh, inputs.load);
}

void run_one(unsigned char rpc, const std::string& body) {
  switch (rpc % 7) {
    case 0: {
      v1::PatchRequest request;
      if (!parse(body, request)) return;
      PatchInputs inputs = prepare_patch(request);
      fuzz::check_loaded(inputs.mesh, inputs.load);
      return;
    }
    case 1: {
      v1::DesignRequest request;
      if (parse(body, request)) check_design(request);
      return;
    }
    case 2: {
      v1::SimulateRequest request;
      if (!parse(body, request)) return;
      prepare_simulation_options(request.options(), "options");
      try {
        design_from_proto(request.design());
      } catch (const Error& e) {
        rethrow_within(e, "design");
      }
      return;
    }
    case 3: {
      v1::RunRequest request;
      if (!parse(body, request)) return;
      prepare_simulation_options(request.simulation(), "simulation");
      check_design(request.design());
      return;
    }
    case 4: {
      v1::GeodesicRequest request;
      if (!parse(body, request)) return;
      GeodesicInputs inputs = prepare_geodesic(request);
      if (inputs.source < 0 || inputs.source >= inputs.mesh.vertex_count())
        fuzz::fail("geodesic source outside the mesh");
      return;
    }
    case 5: {
      v1::LoadRequest request;
      if (!parse(body, request)) return;
      const v1::LoadResult result = run_load(request);
      if (result.mesh().positions_size() % 3 != 0 || result.mesh().indices_size() % 3 != 0)
        fuzz::fail("Load returned ragged packed arrays");
      return;
    }
    default: {
      v1::ExamplesRequest request;
      if (parse(body, request) && run_examples(request).examples_size() == 0)
        fuzz::fail("no examples");
      return;
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const unsigned char* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string body(reinterpret_cast<const char*>(data) + 1, size - 1);
  try {
    run_one(data[0], body);
  } catch (const Error& e) {
    fuzz::expect_invalid_input(e);
  }
  return 0;
}
