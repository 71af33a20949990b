// SPDX-License-Identifier: GPL-3.0-or-later
// libFuzzer target: the HTTP gateway's request decoding for every RPC — protobuf JSON into the
// request message, exactly as server/methods.h parses a body, then the request's checks and
// conversion into kernel inputs (prepare_patch, prepare_design, ...; to_mesh reads mesh files and
// examples). The first byte picks the RPC, the rest is the body. The computations themselves
// (patch, design, deployment) are not run: they are tested on valid inputs elsewhere and would make
// each input seconds long.
#include <google/protobuf/util/json_util.h>

#include <string>

#include "fuzz_support.h"
#include "gridshell/convert_deployment.h"
#include "gridshell/requests.h"
#include "gridshell/v1/requests.pb.h"

namespace {

using namespace gridshell;

template <class Request>
bool parse(const std::string& body, Request& request) {
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = false;  // as the gateway
  return google::protobuf::util::JsonStringToMessage(body, &request, options).ok();
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
