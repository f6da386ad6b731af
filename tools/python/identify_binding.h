#pragma once
// pidlab.identify (identify_binding.cc).

#include <pybind11/pybind11.h>

namespace pidlab::python {

void DefineIdentify(pybind11::module_& m);

}  // namespace pidlab::python
