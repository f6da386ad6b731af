// pidlab-controller: answers every plant output y_k with u_k = PID(r, y_k).

#include "pidlab/controller/controller_role.h"
#include "pidlab/transport/role_main.h"

int main(int argc, char** argv) {
  using namespace pidlab::transport;
  return RoleMain(argc, argv, "pidlab-controller",
                  "pidlab-controller: answers each plant output y_k with u_k = PID(r, y_k) (DiscretePid)",
                  [](Transport* t, LogFn log, bool verbose) {
                    return std::make_unique<pidlab::controller::ControllerRole>(t, log, verbose);
                  });
}
