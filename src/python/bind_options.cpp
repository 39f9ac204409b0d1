#include "python/bind_options.hpp"

#include <pybind11/stl.h>

#include <string>
#include <tuple>
#include <vector>

#include "core/error.hpp"
#include "run/option_help.hpp"
#include "tightex/options.hpp"
#include "tightex/report.hpp"
#include "tightex/run.hpp"

namespace py = pybind11;

namespace tightex {

namespace {

/// The docstring of `field`: its description, as --help gives it.
std::string doc(const char* field) { return std::string(option_help(field)); }

/// A choice field as a string attribute: its name (to_string), set by name (InputError for another).
template <typename Enum, size_t N>
void choice(py::class_<Options>& c, const char* field, Enum Options::*member, const std::array<Enum, N>& values) {
  c.def_property(
      field, [member](const Options& o) { return std::string(to_string(o.*member)); },
      [member, field, &values](Options& o, const std::string& name) {
        const std::optional<Enum> v = from_string(values, name);
        if (!v) fail_input("options: {} '{}' is not one of the names --help lists", field, name);
        o.*member = *v;
      },
      doc(field).c_str());
}

/// An optional choice field: its name, or None.
template <typename Enum, size_t N>
void optional_choice(py::class_<Options>& c, const char* field, std::optional<Enum> Options::*member, const std::array<Enum, N>& values) {
  c.def_property(
      field,
      [member](const Options& o) { return o.*member ? py::object(py::str(std::string(to_string(*(o.*member))))) : py::object(py::none()); },
      [member, field, &values](Options& o, const std::optional<std::string>& name) {
        if (!name) return void(o.*member = std::nullopt);
        const std::optional<Enum> v = from_string(values, *name);
        if (!v) fail_input("options: {} '{}' is not one of the names --help lists", field, *name);
        o.*member = *v;
      },
      doc(field).c_str());
}

/// A Report's JSON as Python objects (the json module's loads), parsed on first use and kept on the
/// object (a Report's JSON never changes).
py::dict parsed(py::object self) {
  if (py::hasattr(self, "_parsed")) return self.attr("_parsed");
  py::dict whole = py::module_::import("json").attr("loads")(self.cast<const Report&>().json);
  self.attr("_parsed") = whole;
  return whole;
}

}  // namespace

void bind_options(py::module_& m) {
  py::class_<Options> c(m, "Options", "What a run chooses; every default is the command's (tightex --help).");
  c.def(py::init<>());
  c.def_readwrite("size", &Options::size, doc("size").c_str());
  c.def_readwrite("texels", &Options::texels, doc("texels").c_str());
  c.def_readwrite("aspect", &Options::aspect,
                  (doc("aspect") + " (0: the square with a size, else chosen per model; -1: chosen per model always)").c_str());
  c.def_readwrite("allow_large_textures", &Options::allow_large_textures, doc("allow_large_textures").c_str());
  c.def_readwrite("allow_outside_files", &Options::allow_outside_files, doc("allow_outside_files").c_str());
  choice(c, "layout", &Options::layout, kLayouts);
  c.def_readwrite("max_page_side", &Options::max_page_side, doc("max_page_side").c_str());
  c.def_readwrite("max_piece_faces", &Options::max_piece_faces, doc("max_piece_faces").c_str());
  choice(c, "holes", &Options::holes, kHoleModes);
  choice(c, "map", &Options::map, kMapKinds);
  c.def_readwrite("balance", &Options::balance, doc("balance").c_str());
  choice(c, "corners", &Options::corners, kCornerRules);
  c.def_readwrite("fit", &Options::fit, doc("fit").c_str());
  c.def_readwrite("fine_fit", &Options::fine_fit, doc("fine_fit").c_str());
  c.def_readwrite("material_map_budget_db", &Options::material_map_budget_db, doc("material_map_budget_db").c_str());
  c.def_readwrite("keep_untextured", &Options::keep_untextured, doc("keep_untextured").c_str());
  c.def_readwrite("measure", &Options::measure, doc("measure").c_str());
  c.def_readwrite("max_memory_mib", &Options::max_memory_mib, doc("max_memory_mib").c_str());
  optional_choice(c, "model_format", &Options::model_format, kModelFormats);
  optional_choice(c, "texture_format", &Options::texture_format, kImageFormats);
  c.def_readwrite("png_level", &Options::png_level, doc("png_level").c_str());
  c.def_readwrite("jpeg_quality", &Options::jpeg_quality, doc("jpeg_quality").c_str());
  c.def_readwrite("webp_quality", &Options::webp_quality, doc("webp_quality").c_str());
  c.def_readwrite("webp_lossless", &Options::webp_lossless, doc("webp_lossless").c_str());
  c.def_readwrite("target_psnr_db", &Options::target_psnr_db, doc("target_psnr_db").c_str());
  c.def_readwrite("max_bytes", &Options::max_bytes, doc("max_bytes").c_str());
  c.def_readwrite("compare_reencode", &Options::compare_reencode, doc("compare_reencode").c_str());
  c.def_readwrite("report_path", &Options::report_path, doc("report_path").c_str());
  c.def_readwrite("preview_path", &Options::preview_path, doc("preview_path").c_str());
  c.def_readwrite("html", &Options::html, doc("html").c_str());
}

void bind_option_table(py::module_& m) {
  m.def(
      "option_flags",
      [] {
        std::vector<std::tuple<std::string, std::string, std::string>> rows;
        for (const OptionHelp& h : option_helps()) rows.emplace_back(h.field, h.flag, h.help);
        return rows;
      },
      "(field, the command's flag, description) of every Options field, as tightex --help lists them");
  m.def("check_options", &check_options, py::arg("options"), "raises InputError for an option out of range or options in conflict");
}

void bind_report(py::module_& m) {
  // dynamic_attr: each Report keeps its parsed JSON (parsed), so that sections are read without parsing
  // the whole text again.
  py::class_<Report> c(m, "Report", py::dynamic_attr(), "What a run did and measured (docs/metrics.md names each figure).");
  c.def_readonly("input_triangles", &Report::input_triangles, "triangles of the input model");
  c.def_readonly("output_triangles", &Report::output_triangles, "triangles of the output model");
  c.def_readonly("components", &Report::components, "connected surfaces after the repair");
  c.def_readonly("charts", &Report::charts, "charts of the output's texture (one per component is the aim)");
  c.def_readonly("lost_triangles", &Report::lost_triangles, "input triangles missing from the output (must be 0)");
  c.def_readonly("flipped_triangles", &Report::flipped_triangles, "output triangles mirrored in texture space (must be 0)");
  c.def_readonly("input_texels_used", &Report::input_texels_used, "share of the input's texels some triangle covers");
  c.def_readonly("output_texels_used", &Report::output_texels_used, "share of the output's texels some triangle covers");
  c.def_readonly("surface_psnr_db", &Report::surface_psnr_db, "surface PSNR of the output as written, in dB");
  c.def_readonly("surface_psnr_bake_db", &Report::surface_psnr_bake_db, "surface PSNR of the bake before encoding, in dB");
  c.def_readonly("texture_sizes", &Report::texture_sizes, "(width, height) of every new texture");
  c.def_readonly("input_texture_bytes", &Report::input_texture_bytes, "bytes of the input's images on disk");
  c.def_readonly("output_texture_bytes", &Report::output_texture_bytes, "bytes of the output's images as written");
  c.def_readonly("texture_format", &Report::texture_format, "the codec of the output's images (png, jpg, webp)");
  c.def_readonly("model_path", &Report::model_path, "the output model's path (empty for optimize_arrays)");
  c.def_readonly("report_path", &Report::report_path, "the report a reader opens: report.html, or report.json");
  c.def_readonly("wall_seconds", &Report::wall_seconds, "the run's wall time in seconds");
  c.def_readonly("peak_rss_mib", &Report::peak_rss_mib, "the most memory the process held, in MiB");
  c.def_readonly("warnings", &Report::warnings, "what a user should read about the result");
  c.def_readonly("notes", &Report::notes, "what the run chose and why, in a line each");
  c.def_readonly("json", &Report::json, "the whole report, as report.json holds it (JSON text)");
  c.def(
      "to_dict", [](py::object self) { return py::module_::import("copy").attr("deepcopy")(parsed(self)); },
      "the whole report as a dict, as report.json holds it (a copy of the one parsed once)");
  c.def(
      "__getitem__", [](py::object self, const std::string& key) { return py::object(parsed(self)[py::str(key)]); },
      "a section of the report (report[\"metrics\"]), as report.json holds it (parsed once, shared: copy it to change it)");
  c.def(
      "__contains__", [](py::object self, const std::string& key) { return parsed(self).contains(py::str(key)); },
      "whether the report has the section `key`");
}

}  // namespace tightex
