// tetrapage's exceptions as Python exceptions carrying the C++ message. InputError is also a
// ValueError and IoError an OSError, so that code catching the built-in kinds catches ours.

#include <Python.h>

#include "Bindings.h"
#include "tetrapage/formats/base/Error.h"

namespace tetrapage::python {

namespace {

// Created once with the module and never freed (the module lives until the interpreter ends).
PyObject* error_type = nullptr;
PyObject* io_error_type = nullptr;
PyObject* format_error_type = nullptr;
PyObject* input_error_type = nullptr;

PyObject* new_exception(py::module_& module, const char* name, const char* doc, py::tuple bases) {
  const std::string qualified = "tetrapage." + std::string(name);
  PyObject* type = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases.ptr(), nullptr);
  if (type == nullptr) throw py::error_already_set();
  module.add_object(name, py::handle(type));  // add_object steals: keep ours
  Py_INCREF(type);
  return type;
}

}  // namespace

void bind_errors(py::module_& module) {
  error_type = new_exception(module, "Error", "Base of every tetrapage error.",
                             py::make_tuple(py::handle(PyExc_Exception)));
  io_error_type =
      new_exception(module, "IoError", "A file could not be opened, read, written or renamed.",
                    py::make_tuple(py::handle(error_type), py::handle(PyExc_OSError)));
  format_error_type =
      new_exception(module, "FormatError", "A file's contents are not what its format requires.",
                    py::make_tuple(py::handle(error_type)));
  input_error_type = new_exception(
      module, "InputError",
      "Well-formed but unusable input: NaN, an index out of range, a wrong dtype or shape, "
      "a non-unit quaternion, an invalid option.",
      py::make_tuple(py::handle(error_type), py::handle(PyExc_ValueError)));
  py::register_exception_translator([](std::exception_ptr thrown) {
    try {
      if (thrown) std::rethrow_exception(thrown);
    } catch (const InputError& error) {
      PyErr_SetString(input_error_type, error.what());
    } catch (const FormatError& error) {
      PyErr_SetString(format_error_type, error.what());
    } catch (const IoError& error) {
      PyErr_SetString(io_error_type, error.what());
    } catch (const Error& error) {
      PyErr_SetString(error_type, error.what());
    }
  });
}

}  // namespace tetrapage::python
