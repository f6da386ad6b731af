// pidlab-controller: answers every plant output y_k with u_k = PID(r, y_k).

#include "pidlab/lcm/process_main.h"

int main(int argc, char** argv) {
  using namespace pidlab::lcm_trio;
  return RoleMain(argc, argv, "pidlab-controller",
                  "pidlab-controller: answers each plant output y_k with u_k = PID(r, y_k) (DiscretePid)",
                  [](Transport* t, LogFn log, bool verbose) {
                    return std::make_unique<ControllerRole>(t, log, verbose);
                  });
}
