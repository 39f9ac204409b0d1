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

/// The report's JSON as Python objects (the json module's loads).
py::object loads(const std::string& text) { return py::module_::import("json").attr("loads")(text); }

}  // namespace

void bind_options(py::module_& m) {
  py::class_<Options> c(m, "Options", "What a run chooses; every default is the command's (tightex --help).");
  c.def(py::init<>());
  c.def_readwrite("size", &Options::size, doc("size").c_str());
  c.def_readwrite("texels", &Options::texels, doc("texels").c_str());
  c.def_readwrite("aspect", &Options::aspect, (doc("aspect") + " (0: auto)").c_str());
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
  py::class_<Report> c(m, "Report", "What a run did and measured (docs/metrics.md names each figure).");
  c.def_readonly("input_triangles", &Report::input_triangles);
  c.def_readonly("output_triangles", &Report::output_triangles);
  c.def_readonly("components", &Report::components);
  c.def_readonly("charts", &Report::charts);
  c.def_readonly("lost_triangles", &Report::lost_triangles);
  c.def_readonly("flipped_triangles", &Report::flipped_triangles);
  c.def_readonly("input_texels_used", &Report::input_texels_used);
  c.def_readonly("output_texels_used", &Report::output_texels_used);
  c.def_readonly("surface_psnr_db", &Report::surface_psnr_db);
  c.def_readonly("surface_psnr_bake_db", &Report::surface_psnr_bake_db);
  c.def_readonly("texture_sizes", &Report::texture_sizes);
  c.def_readonly("input_texture_bytes", &Report::input_texture_bytes);
  c.def_readonly("output_texture_bytes", &Report::output_texture_bytes);
  c.def_readonly("texture_format", &Report::texture_format);
  c.def_readonly("model_path", &Report::model_path);
  c.def_readonly("report_path", &Report::report_path);
  c.def_readonly("wall_seconds", &Report::wall_seconds);
  c.def_readonly("peak_rss_mib", &Report::peak_rss_mib);
  c.def_readonly("warnings", &Report::warnings);
  c.def_readonly("notes", &Report::notes);
  c.def_readonly("json", &Report::json, "the whole report, as report.json holds it (JSON text)");
  c.def("to_dict", [](const Report& r) { return loads(r.json); }, "the whole report as a dict, as report.json holds it");
  c.def(
      "__getitem__",
      [](const Report& r, const std::string& key) {
        const py::object whole = loads(r.json);
        return py::object(whole[py::str(key)]);  // owned: the accessor alone would outlive `whole`
      },
        "a section of the report (report[\"metrics\"]), as report.json holds it");
  c.def("__contains__", [](const Report& r, const std::string& key) { return loads(r.json).contains(py::str(key)); });
}

}  // namespace tightex
