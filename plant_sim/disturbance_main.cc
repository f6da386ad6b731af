// pidlab-disturbance: answers the plant's requests for disturbance samples
// with blocks of n_k = n(k dt). It never sees y_k (n does not depend on it).

#include "pidlab/plant_sim/disturbance_role.h"
#include "pidlab/transport/role_main.h"

int main(int argc, char** argv) {
  using namespace pidlab::transport;
  return RoleMain(argc, argv, "pidlab-disturbance",
                  "pidlab-disturbance: answers the plant's DISTURBANCE_REQUESTs with blocks of n_k = n(k dt)",
                  [](Transport* t, LogFn log, bool verbose) {
                    return std::make_unique<pidlab::plant_sim::DisturbanceRole>(t, log, verbose);
                  });
}
