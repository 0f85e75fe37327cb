// ivoa-test-random-model OUT.pt: an untrained (random-weight) introspection
// model file, so end-to-end tests can run ivoa-introspection where no
// trained model is shipped. Its predictions mean nothing.
#include <cstdio>

#include <torch/torch.h>

#include "ivoa/introspection/model.hpp"
#include "model_file.hpp"
#include "networks.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s OUT.pt\n", argv[0]);
    return 2;
  }
  using namespace ivoa::introspection;
  torch::manual_seed(1);
  const std::string architecture = "slidenet";
  auto net = make_network(architecture, 0.5);
  ModelInfo info;
  info.architecture = architecture;
  info.input_size = input_size_of(architecture);
  info.detector = "jppc";
  info.training_summary = "{\"untrained\": true}";
  try {
    save_model(*net, info, argv[1]);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "cannot write %s: %s\n", argv[1], e.what());
    return 4;
  }
  return 0;
}
