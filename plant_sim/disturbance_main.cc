// pidlab-disturbance: answers every plant output y_k with n_k = n(k dt).

#include "pidlab/lcm/process_main.h"

int main(int argc, char** argv) {
  using namespace pidlab::lcm_trio;
  return RoleMain(
      argc, argv, "pidlab-disturbance",
      "pidlab-disturbance: answers each plant output y_k with the disturbance sample n_k = n(k dt)",
      [](Transport* t, LogFn log, bool verbose) {
        return std::make_unique<DisturbanceRole>(t, log, verbose);
      });
}
