// tightex._tightex: the C++ half of the Python module `tightex` (python/tightex/__init__.py wraps it).
// Options and Report are the library's own types (bind_options.cpp); errors arrive as tightex.InputError, InternalError and Cancelled,
// subclasses of tightex.Error. The GIL is released while tightex works; the progress callback takes it back.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <tbb/global_control.h>

#include <cstring>
#include <exception>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "python/bind_options.hpp"
#include "report/html_report.hpp"
#include "tightex/io.hpp"
#include "tightex/run.hpp"
#include "tightex/tightex.hpp"
#include "tightex/version.hpp"

namespace py = pybind11;
using namespace tightex;

namespace {

/// The progress callback handed to tightex: calls the Python callable with the GIL held (tightex calls
/// it from its worker threads too). Returning False cancels; an exception the callable raises also
/// cancels and is raised again once tightex has stopped (rethrow_if_raised).
class PythonProgress {
 public:
  explicit PythonProgress(py::object callable) : callable_(std::move(callable)) {}

  ProgressCallback callback() {
    if (callable_.is_none()) return {};
    return [this](std::string_view stage, double fraction) {
      py::gil_scoped_acquire gil;
      try {
        const py::object answer = callable_(std::string(stage), fraction);
        return answer.is_none() || answer.cast<bool>();
      } catch (py::error_already_set& e) {
        std::lock_guard lock(mutex_);
        if (!raised_) raised_ = std::current_exception();
        return false;
      }
    };
  }
  void rethrow_if_raised() {
    if (raised_) std::rethrow_exception(raised_);
  }

 private:
  py::object callable_;
  std::mutex mutex_;
  std::exception_ptr raised_;
};

/// Runs `work` without the GIL; an exception the progress callable raised wins over the Cancelled it
/// caused.
template <typename Work>
auto without_gil(PythonProgress& progress, Work&& work) {
  try {
    py::gil_scoped_release release;
    return work();
  } catch (const Cancelled&) {
    progress.rethrow_if_raised();
    throw;
  }
}

/// tightex.run: the library's run on a model file.
Report run_file(const std::string& input, const std::string& outdir, Options options, py::object progress_callable) {
  PythonProgress progress(std::move(progress_callable));
  options.progress = progress.callback();
  return without_gil(progress, [&] { return run(input, outdir, options); });
}

/// tightex.estimate_memory: the bytes the run's memory guard estimates for this model and options.
double estimate_file_memory(const std::string& input, const Options& options) {
  py::gil_scoped_release release;
  return estimate_memory(input, options);
}

/// tightex.set_max_threads: at most `n` threads for tightex's parallel work in this process from now
/// on (0: as many as cores). A Dask worker sharing a machine with others takes its share of the cores.
void set_max_threads(int n) {
  static std::unique_ptr<tbb::global_control> limit;
  limit.reset();
  if (n > 0) limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, size_t(n));
}

using Doubles = py::array_t<double, py::array::c_style | py::array::forcecast>;
using Indices = py::array_t<int64_t, py::array::c_style | py::array::forcecast>;
using Bytes = py::array_t<uint8_t, py::array::c_style | py::array::forcecast>;

/// Throws InputError unless `a` has the shape `want` (-1: any extent).
void check_shape(const py::array& a, const char* name, std::vector<py::ssize_t> want) {
  bool ok = a.ndim() == py::ssize_t(want.size());
  for (size_t i = 0; ok && i < want.size(); ++i) ok = want[i] < 0 || a.shape(py::ssize_t(i)) == want[i];
  if (ok) return;
  std::string got, expected;
  for (py::ssize_t i = 0; i < a.ndim(); ++i) got += (i ? ", " : "") + std::to_string(a.shape(i));
  for (size_t i = 0; i < want.size(); ++i) expected += (i ? ", " : "") + (want[i] < 0 ? std::string("N") : std::to_string(want[i]));
  throw InputError(std::string("arrays: ") + name + " has shape (" + got + "), expected (" + expected + ")");
}

/// An HxWx3 or HxWx4 uint8 array as an RGBA image.
Image image_from_array(const Bytes& a, size_t index) {
  const std::string name = "images[" + std::to_string(index) + "]";
  if (a.ndim() != 3 || (a.shape(2) != 3 && a.shape(2) != 4) || a.shape(0) < 1 || a.shape(1) < 1)
    throw InputError("arrays: " + name + " must be an H x W x 3 or H x W x 4 uint8 array");
  const int h = int(a.shape(0)), w = int(a.shape(1)), c = int(a.shape(2));
  Image image(w, h);
  const uint8_t* p = a.data();
  for (size_t i = 0; i < image.pixels.size(); ++i, p += c) image.pixels[i] = Rgba8{p[0], p[1], p[2], c == 4 ? p[3] : uint8_t(255)};
  return image;
}

/// Checks every index of `a` is in [lo, hi); throws InputError naming `name` otherwise.
void check_indices(const Indices& a, const char* name, int64_t lo, int64_t hi) {
  const int64_t* p = a.data();
  for (py::ssize_t i = 0; i < a.size(); ++i)
    if (p[i] < lo || p[i] >= hi)
      throw InputError(std::string("arrays: ") + name + " element " + std::to_string(i) + " is " + std::to_string(p[i]) + ", outside [" +
                       std::to_string(lo) + ", " + std::to_string(hi) + ")");
}

/// The corner texture coordinates: `uvs` (F,3,2) per corner, or (T,2) indexed by `face_uvs` (F,3), or
/// (V,2) per vertex without face_uvs.
std::vector<Vec2> corner_uvs(const Doubles& uvs, const py::object& face_uvs, const Indices& faces, size_t num_vertices) {
  const size_t f = size_t(faces.shape(0));
  std::vector<Vec2> out(3 * f);
  const double* uv = uvs.data();
  if (uvs.ndim() == 3) {
    check_shape(uvs, "uvs", {py::ssize_t(f), 3, 2});
    for (size_t i = 0; i < 3 * f; ++i) out[i] = Vec2(uv[2 * i], uv[2 * i + 1]);
    return out;
  }
  check_shape(uvs, "uvs", {-1, 2});
  Indices index = faces;
  if (!face_uvs.is_none()) {
    index = face_uvs.cast<Indices>();
    check_shape(index, "face_uvs", {py::ssize_t(f), 3});
  } else if (size_t(uvs.shape(0)) != num_vertices) {
    throw InputError("arrays: uvs has " + std::to_string(uvs.shape(0)) + " rows but positions has " + std::to_string(num_vertices) +
                     " (per-vertex uvs need one per position; else give face_uvs or (F, 3, 2) uvs)");
  }
  check_indices(index, face_uvs.is_none() ? "faces" : "face_uvs", 0, uvs.shape(0));
  const int64_t* p = index.data();
  for (size_t i = 0; i < 3 * f; ++i) out[i] = Vec2(uv[2 * p[i]], uv[2 * p[i] + 1]);
  return out;
}

/// The material slot named `name` ("normal", "metallic_roughness", ...); InputError for another name.
MaterialSlot slot_named(const std::string& name, size_t material) {
  for (size_t s = 0; s < kMaterialSlots; ++s)
    if (name == material_slot_name(MaterialSlot(s))) return MaterialSlot(s);
  throw InputError("arrays: materials[" + std::to_string(material) + "] maps '" + name + "', not a material slot");
}

/// A material given as a dict: "texture" (its base colour image, -1: none), "kd" (its linear base colour
/// factor), "maps" ({slot name: image index}).
Material material_from_dict(const py::dict& d, size_t index, size_t num_images) {
  Material m{"material_" + std::to_string(index), {1.0, 1.0, 1.0}, -1};
  const auto image_index = [&](const py::handle& h, const std::string& what) {
    const int i = h.cast<int>();
    if (i < -1 || i >= int(num_images))
      throw InputError("arrays: materials[" + std::to_string(index) + "] " + what + " is image " + std::to_string(i) + ", outside [-1, " +
                       std::to_string(num_images) + ")");
    return i;
  };
  if (d.contains("texture")) m.texture = image_index(d["texture"], "texture");
  if (d.contains("kd")) m.kd = d["kd"].cast<std::array<double, 3>>();
  if (d.contains("maps"))
    for (const auto& [slot, image] : d["maps"].cast<py::dict>())
      m.maps[size_t(slot_named(slot.cast<std::string>(), index))] = image_index(image, "map " + slot.cast<std::string>());
  return m;
}

/// The mesh's materials: one per image (the default), or `materials` (a list of dicts) where given.
void set_materials(TexturedMesh& mesh, const py::object& materials) {
  if (materials.is_none()) {
    for (size_t i = 0; i < mesh.textures.size(); ++i)
      mesh.materials.push_back(Material{"material_" + std::to_string(i), {1.0, 1.0, 1.0}, int(i)});
    return;
  }
  const py::list list = materials.cast<py::list>();
  for (size_t i = 0; i < list.size(); ++i) mesh.materials.push_back(material_from_dict(list[i].cast<py::dict>(), i, mesh.textures.size()));
}

/// Vertex colours (F,3,4) per corner, sRGB in [0, 1], baked into a texture as the readers' are.
void set_colours(TexturedMesh& mesh, const py::object& colours) {
  if (colours.is_none()) return;
  const auto c = colours.cast<py::array_t<float, py::array::c_style | py::array::forcecast>>();
  check_shape(c, "colors", {py::ssize_t(mesh.num_triangles()), 3, 4});
  mesh.corner_color.resize(3 * mesh.num_triangles());
  std::memcpy(static_cast<void*>(mesh.corner_color.data()), c.data(), mesh.corner_color.size() * 4 * sizeof(float));
  texture_vertex_colours(mesh);
}

/// A TexturedMesh from NumPy arrays: one material per image unless `materials` names them,
/// `material_ids` (F,) the material of each face (-1: none; default: all the first).
TexturedMesh mesh_from_arrays(const Doubles& positions, const Indices& faces, const Doubles& uvs, const std::vector<Bytes>& images,
                              const py::object& material_ids, const py::object& face_uvs, const py::object& materials,
                              const py::object& colours) {
  check_shape(positions, "positions", {-1, 3});
  check_shape(faces, "faces", {-1, 3});
  if (images.empty() && materials.is_none() && colours.is_none())
    throw InputError("arrays: images is empty; give at least one texture image");
  TexturedMesh mesh;
  mesh.source = "arrays";
  const size_t v = size_t(positions.shape(0)), f = size_t(faces.shape(0));
  check_indices(faces, "faces", 0, int64_t(v));
  mesh.positions.resize(v);
  std::memcpy(static_cast<void*>(mesh.positions.data()), positions.data(), v * 3 * sizeof(double));
  mesh.triangles.resize(f);
  const int64_t* fp = faces.data();
  for (size_t i = 0; i < f; ++i) mesh.triangles[i] = Tri{uint32_t(fp[3 * i]), uint32_t(fp[3 * i + 1]), uint32_t(fp[3 * i + 2])};
  mesh.corner_uv = corner_uvs(uvs, face_uvs, faces, v);
  for (size_t i = 0; i < images.size(); ++i) {
    Texture t{"texture_" + std::to_string(i), image_from_array(images[i], i)};
    t.width = t.image.width, t.height = t.image.height;
    mesh.textures.push_back(std::move(t));
  }
  set_materials(mesh, materials);
  mesh.face_material.assign(f, mesh.materials.empty() ? -1 : 0);
  if (!material_ids.is_none()) {
    const Indices ids = material_ids.cast<Indices>();
    check_shape(ids, "material_ids", {py::ssize_t(f)});
    check_indices(ids, "material_ids", -1, int64_t(mesh.materials.size()));
    for (size_t i = 0; i < f; ++i) mesh.face_material[i] = int32_t(ids.data()[i]);
  }
  set_colours(mesh, colours);
  return mesh;
}

/// The output's materials as dicts ("texture", "kd", "maps" {slot name: image}), as `materials` takes them,
/// with their "name" (the input material's) and "new": whether its base colour is one of the first
/// `new_images` images (the new ones) rather than an input image kept as it was.
py::list material_dicts(const TexturedMesh& mesh, size_t new_images) {
  py::list out;
  for (const Material& m : mesh.materials) {
    py::dict maps;
    for (size_t s = 0; s < kMaterialSlots; ++s)
      if (m.maps[s] >= 0) maps[py::str(material_slot_name(MaterialSlot(s)))] = m.maps[s];
    py::dict d;
    d["name"] = m.name, d["texture"] = m.texture, d["kd"] = m.kd, d["maps"] = maps;
    d["new"] = m.texture >= 0 && size_t(m.texture) < new_images;
    out.append(d);
  }
  return out;
}

/// The output mesh as a dict of NumPy arrays (positions, faces, uvs (F,3,2) as sampled, material_ids:
/// each face's image, images) and the report as JSON text.
py::dict arrays_from_mesh(const TexturedMesh& mesh, size_t new_images) {
  const py::ssize_t v = py::ssize_t(mesh.num_vertices()), f = py::ssize_t(mesh.num_triangles());
  py::array_t<double> positions({v, py::ssize_t(3)});
  std::memcpy(positions.mutable_data(), static_cast<const void*>(mesh.positions.data()), size_t(v) * 3 * sizeof(double));
  py::array_t<int64_t> faces({f, py::ssize_t(3)});
  py::array_t<double> uvs({f, py::ssize_t(3), py::ssize_t(2)});
  py::array_t<int64_t> ids(f), face_materials(f), input_triangles(f);
  for (py::ssize_t t = 0; t < f; ++t) {
    const int m = mesh.face_material[size_t(t)];
    ids.mutable_at(t) = m < 0 ? -1 : mesh.materials[size_t(m)].texture;
    face_materials.mutable_at(t) = m;
    input_triangles.mutable_at(t) = mesh.input_triangle.empty() ? t : int64_t(mesh.input_triangle[size_t(t)]);
    for (int c = 0; c < 3; ++c) {
      faces.mutable_at(t, c) = mesh.triangles[size_t(t)][size_t(c)];
      const Vec2 uv = mesh.sampled_uv(size_t(t), c);
      uvs.mutable_at(t, c, 0) = uv.x(), uvs.mutable_at(t, c, 1) = uv.y();
    }
  }
  py::list images;
  for (const Texture& t : mesh.textures) {
    py::array_t<uint8_t> image({py::ssize_t(t.image.height), py::ssize_t(t.image.width), py::ssize_t(4)});
    std::memcpy(image.mutable_data(), static_cast<const void*>(t.image.pixels.data()), t.image.pixels.size() * 4);
    images.append(image);
  }
  py::dict out;
  out["positions"] = positions, out["faces"] = faces, out["uvs"] = uvs, out["material_ids"] = ids, out["images"] = images;
  out["face_materials"] = face_materials, out["input_triangles"] = input_triangles, out["materials"] = material_dicts(mesh, new_images);
  return out;
}

/// tightex.optimize_arrays: the library on an in-memory mesh; the arrays out and the report (with
/// "report_html", the report.html page's text, where `html`).
py::tuple optimize_arrays(const Doubles& positions, const Indices& faces, const Doubles& uvs, const std::vector<Bytes>& images,
                          const py::object& material_ids, const py::object& face_uvs, Options options, py::object progress_callable,
                          const py::object& materials, const py::object& colours, bool html) {
  const TexturedMesh mesh = mesh_from_arrays(positions, faces, uvs, images, material_ids, face_uvs, materials, colours);
  PythonProgress progress(std::move(progress_callable));
  options.progress = progress.callback();
  options.measure = true;
  const Result result = without_gil(progress, [&] { return optimize(mesh, options); });
  py::dict arrays = arrays_from_mesh(result.output, result.report.texture_sizes.size());
  if (html) {
    std::string page;
    {
      py::gil_scoped_release release;
      page = html_report_page(result.report.json, html_model_data(mesh, result.output));
    }
    arrays["report_html"] = page;
  }
  return py::make_tuple(arrays, result.report);
}

}  // namespace

PYBIND11_MODULE(_tightex, m) {
  m.doc() = "tightex's C++ core; use the package `tightex`, which wraps it.";
  m.attr("__version__") = std::string(version());  // the same string as `tightex --version`
  static py::exception<std::runtime_error> error(m, "Error");
  error.attr("__module__") = "tightex";
  error.attr("__doc__") = "Base class of every error tightex raises.";
  static py::exception<InputError> input_error(m, "InputError", error.ptr());
  input_error.attr("__module__") = "tightex";
  input_error.attr("__doc__") = "Bad input: the one-line message names the file (or array), the element and the problem.";
  static py::exception<InternalError> internal_error(m, "InternalError", error.ptr());
  internal_error.attr("__module__") = "tightex";
  internal_error.attr("__doc__") = "A broken invariant inside tightex (a bug: please report it with the input).";
  static py::exception<Cancelled> cancelled(m, "Cancelled", error.ptr());
  cancelled.attr("__module__") = "tightex";
  cancelled.attr("__doc__") = "The progress callback returned False: the run stopped and nothing was written.";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      PyErr_SetString(input_error.ptr(), e.what());
    } catch (const InternalError& e) {
      PyErr_SetString(internal_error.ptr(), e.what());
    } catch (const Cancelled& e) {
      PyErr_SetString(cancelled.ptr(), e.what());
    }
  });
  bind_options(m);
  bind_option_table(m);
  bind_report(m);
  m.def("run", &run_file, py::arg("input"), py::arg("outdir"), py::arg("options"), py::arg("progress"));
  m.def("set_max_threads", &set_max_threads, py::arg("n"));
  m.def("estimate_memory", &estimate_file_memory, py::arg("input"), py::arg("options"));
  m.def("optimize_arrays", &optimize_arrays, py::arg("positions"), py::arg("faces"), py::arg("uvs"), py::arg("images"),
        py::arg("material_ids"), py::arg("face_uvs"), py::arg("options"), py::arg("progress"), py::arg("materials") = py::none(),
        py::arg("colors") = py::none(), py::arg("html") = false);
}
