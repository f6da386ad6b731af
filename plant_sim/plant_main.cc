// pidlab-plant: the plant of the trio. Steps the exactly discretised plant
// (DiscretePlant) in lockstep with pidlab-controller and pidlab-disturbance.

#include "pidlab/plant_sim/plant_role.h"
#include "pidlab/transport/role_main.h"

int main(int argc, char** argv) {
  using namespace pidlab::transport;
  RealtimeFlags realtime;
  return RoleMain(
      argc, argv, "pidlab-plant",
      "pidlab-plant: publishes y_k, waits for u_k and n_k, steps x_{k+1} = Phi x_k + Gamma (u_k + n_k)",
      [&realtime](Transport* t, LogFn log, bool verbose) {
        return std::make_unique<pidlab::plant_sim::PlantRole>(t, log, verbose, realtime.factor);
      },
      &realtime);
}
