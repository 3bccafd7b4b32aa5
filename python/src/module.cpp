// The Python module solo._solo (docs/python.md): the pipeline library's stages on numpy arrays,
// its errors as Python exceptions carrying the messages the solo binary prints.

#include "bindings.h"

#include <solo/core/error.h>
#include <solo/core/version.h>
#include <solo/pipeline/large_buffer_allocator.h>
#include <solo/pipeline/night_job.h>

#include <pybind11/stl.h>

#include <cerrno>
#include <filesystem>

namespace solo::python {

namespace {

PyObject* input_error = nullptr;          // solo.InputError(ValueError)
PyObject* missing_input_error = nullptr;  // solo.MissingInputError(InputError, FileNotFoundError)

/// A missing input: the library's "file not found", or a file it could not open that does not exist.
bool isMissingFile(const InputError& e) {
  if (e.problem().rfind("file not found", 0) == 0) return true;
  std::error_code ec;
  return e.problem().rfind("cannot open for reading", 0) == 0 && !std::filesystem::exists(e.file(), ec);
}

/// Raises `type`(message) with .file and .problem set (not OSError's .filename: str() would add it).
void raiseInputError(PyObject* type, const InputError& e) {
  py::object error = py::reinterpret_steal<py::object>(PyObject_CallFunction(type, "s", e.what()));
  if (!error) return;  // the Python error of the failed call stays set
  error.attr("file") = e.file().string();
  error.attr("problem") = e.problem();
  PyErr_SetObject(type, error.ptr());
}

void translateErrors(std::exception_ptr p) {
  try {
    if (p) std::rethrow_exception(p);
  } catch (const InputError& e) {
    raiseInputError(isMissingFile(e) ? missing_input_error : input_error, e);
  } catch (const std::filesystem::filesystem_error& e) {
    // As the binary prints it: the path, then the system's message.
    const std::string message =
        (e.path1().empty() ? std::string() : e.path1().string() + ": ") + e.code().message();
    PyErr_SetString(e.code() == std::errc::no_such_file_or_directory ? PyExc_FileNotFoundError : PyExc_OSError,
                    message.c_str());
  }
}

}  // namespace

void bindErrors(py::module_& m) {
  input_error = PyErr_NewExceptionWithDoc(
      "solo._solo.InputError",
      "A file or value given to solo cannot be used. str() is \"<file or option>: <problem>\", the message "
      "the solo binary prints; .file and .problem hold its two parts.",
      PyExc_ValueError, nullptr);
  const py::tuple bases = py::make_tuple(py::handle(input_error), py::handle(PyExc_FileNotFoundError));
  missing_input_error = PyErr_NewExceptionWithDoc(
      "solo._solo.MissingInputError", "An input file that does not exist (an InputError and a FileNotFoundError).",
      bases.ptr(), nullptr);
  m.add_object("InputError", py::handle(input_error));
  m.add_object("MissingInputError", py::handle(missing_input_error));
  py::register_exception_translator(&translateErrors);
}

}  // namespace solo::python

PYBIND11_MODULE(_solo, m) {
  namespace sp = solo::python;
  namespace py = pybind11;
  m.doc() = "solo: day-to-night street scenes with physically based 3D geometry and lighting (docs/python.md)";
  m.attr("__version__") = solo::soloVersion();
  // As the binary does: freed buffers of the stages stay in the heap for the next stage and run
  // (large_buffer_allocator.h); without it a conversion spends seconds in page faults.
  solo::keepFreedLargeBuffersForReuse();
  m.def("versions", [] {
    auto list = solo::pipelineDependencyVersions();
    list.insert(list.begin(), {"solo", solo::soloVersion()});
    py::dict out;
    for (const auto& [name, version] : list) out[py::str(name)] = version;
    return out;
  }, "solo's version and those of the libraries it was built against, name -> version.");
  sp::bindErrors(m);
  sp::bindScene(m);
  sp::bindGeometry(m);
  sp::bindLighting(m);
  sp::bindNight(m);
  sp::bindPost(m);
  sp::bindEval(m);
}
