#include "unjam/packing/export.hpp"

#include <algorithm>
#include <cstdint>
#include <functional>
#include <utility>

#include "unjam/core/error.hpp"
#include "unjam/core/version.hpp"
#include "unjam/packing/csv_table.hpp"

namespace unjam {
namespace {

// Points of the .vtp: the grains, then the periodic images of b for the contacts that cross
// the boundary. grain[p] is the grain of point p; end[k] the point where line k ends.
struct LineGeometry {
  std::vector<Vec2> position;
  std::vector<int> grain;
  std::vector<int> end;
};

LineGeometry line_geometry(const Packing& p) {
  LineGeometry g;
  for (std::size_t i = 0; i < p.size(); ++i) {
    g.position.push_back(p.particles.position(i));
    g.grain.push_back(static_cast<int>(i));
  }
  const double half = 0.5 * std::min(p.cell.Lx, p.cell.Ly);
  for (const Contact& c : p.contacts) {
    const Vec2 tip = p.particles.position(c.a) + c.l;
    if ((tip - p.particles.position(c.b)).norm() < half) {
      g.end.push_back(c.b);
      continue;
    }
    g.end.push_back(static_cast<int>(g.position.size()));
    g.position.push_back(tip);
    g.grain.push_back(c.b);
  }
  return g;
}

// One <DataArray> of `count` tuples of `components` values value(i, c).
void data_array(std::string& out, const char* type, const std::string& name, std::size_t count,
                int components, const std::function<double(std::size_t, int)>& value) {
  out += "        <DataArray type=\"";
  out += type;
  out += '"';
  if (!name.empty()) out += " Name=\"" + name + '"';
  out += " NumberOfComponents=\"" + std::to_string(components) + "\" format=\"ascii\">\n";
  const bool integral = type[0] != 'F';
  for (std::size_t i = 0; i < count; ++i) {
    out += "          ";
    for (int c = 0; c < components; ++c) {
      if (c > 0) out += ' ';
      const double v = value(i, c);
      if (integral) append_number(out, static_cast<std::int64_t>(v));
      else append_number(out, v);
    }
    out += '\n';
  }
  out += "        </DataArray>\n";
}

// A vtkStringArray in ASCII: every character as its byte value, the string ended by 0.
void string_array(std::string& out, const std::string& name, const std::string& text) {
  out += "      <DataArray type=\"String\" Name=\"" + name +
         "\" NumberOfTuples=\"1\" format=\"ascii\">\n        ";
  for (const unsigned char ch : text) out += std::to_string(int(ch)) + ' ';
  out += "0\n      </DataArray>\n";
}

void field_data(std::string& out, const Packing& p, const GrainDisplacement* field,
                const ExportRecord& record) {
  out += "    <FieldData>\n";
  const std::pair<const char*, double> numbers[] = {
      {"Lx", p.cell.Lx}, {"Ly", p.cell.Ly}, {"mu", p.meta.contact.mu}, {"P_ext", p.meta.contact.P_ext},
      {"F0", p.force_unit()}, {"probed_contact", field ? double(field->contact) : -1.0}};
  for (const auto& [name, v] : numbers) {
    out += "      <DataArray type=\"Float64\" Name=\"" + std::string(name) +
           "\" NumberOfTuples=\"1\" format=\"ascii\">";
    append_number(out, v);
    out += "</DataArray>\n";
  }
  out += "      <DataArray type=\"UInt64\" Name=\"seed\" NumberOfTuples=\"1\" format=\"ascii\">" +
         std::to_string(p.meta.seed) + "</DataArray>\n";
  string_array(out, "program_version", kVersion);
  string_array(out, "source", record.source);
  string_array(out, "command", record.command);
  out += "    </FieldData>\n";
}

void point_data(std::string& out, const Packing& p, const LineGeometry& g,
                const GrainDisplacement* field) {
  const auto& P = p.particles;
  const std::size_t n = g.position.size();
  const auto per_grain = [&](const std::vector<double>& v) {
    return [&v, &g](std::size_t i, int) { return v[g.grain[i]]; };
  };
  const auto vec3 = [&](const std::vector<Vec2>& v) {
    return [&v, &g](std::size_t i, int c) { return c < 2 ? v[g.grain[i]][c] : 0.0; };
  };
  out += "      <PointData Scalars=\"radius\">\n";
  data_array(out, "Int64", "id", n, 1, [&](std::size_t i, int) { return g.grain[i]; });
  data_array(out, "UInt8", "image", n, 1, [&](std::size_t i, int) { return i >= p.size(); });
  data_array(out, "Float64", "radius", n, 1, per_grain(P.radius));
  data_array(out, "Float64", "velocity", n, 3, [&](std::size_t i, int c) {
    return c == 0 ? P.vx[g.grain[i]] : c == 1 ? P.vy[g.grain[i]] : 0.0;
  });
  data_array(out, "Float64", "omega", n, 1, per_grain(P.omega));
  if (field) {
    data_array(out, "Float64", "displacement", n, 3, vec3(field->u));
    data_array(out, "Float64", "displacement_over_g", n, 3, vec3(field->u_over_g));
    data_array(out, "Float64", "rotation", n, 1, per_grain(field->rot));
  }
  out += "      </PointData>\n";
}

void cell_data(std::string& out, const Packing& p) {
  const std::size_t m = p.contacts.size();
  const auto& C = p.contacts;
  const double F0 = p.force_unit();
  out += "      <CellData Scalars=\"fn\">\n";
  data_array(out, "Int64", "contact", m, 1, [](std::size_t k, int) { return double(k); });
  data_array(out, "Int64", "a", m, 1, [&](std::size_t k, int) { return C[k].a; });
  data_array(out, "Int64", "b", m, 1, [&](std::size_t k, int) { return C[k].b; });
  data_array(out, "Float64", "fn", m, 1, [&](std::size_t k, int) { return C[k].fn; });
  data_array(out, "Float64", "ft", m, 1, [&](std::size_t k, int) { return C[k].ft; });
  data_array(out, "Float64", "fn_over_F0", m, 1, [&](std::size_t k, int) { return C[k].fn / F0; });
  data_array(out, "Int32", "state", m, 1, [&](std::size_t k, int) {
    return double(contact_state(C[k].fn, C[k].ft, p.meta.contact.mu, kExportStateTol * F0));
  });
  out += "      </CellData>\n";
}

void check_field(const Packing& p, const GrainDisplacement* field) {
  if (field && (field->u.size() != p.size() || field->u_over_g.size() != p.size() ||
                field->rot.size() != p.size()))
    throw Error("export: the displacement field has " + std::to_string(field->u.size()) +
                " grains, the packing " + std::to_string(p.size()));
}

}  // namespace

GrainDisplacement read_displacement_csv(const std::filesystem::path& path, std::size_t N) {
  const CsvTable t = CsvTable::read(path);
  if (t.rows() != N)
    throw Error(path.string() + ": " + std::to_string(t.rows()) + " grains, the packing has " +
                std::to_string(N));
  const std::size_t id = t.column("id"), ux = t.column("ux"), uy = t.column("uy"),
                    rot = t.column("rot"), uxg = t.column("ux_g"), uyg = t.column("uy_g");
  GrainDisplacement f;
  f.u.resize(N);
  f.u_over_g.resize(N);
  f.rot.resize(N);
  for (std::size_t r = 0; r < N; ++r) {
    if (t.integer(r, id) != static_cast<std::int64_t>(r)) t.fail(r, "ids must be 0 .. N-1 in order");
    f.u[r] = {t.number(r, ux), t.number(r, uy)};
    f.u_over_g[r] = {t.number(r, uxg), t.number(r, uyg)};
    f.rot[r] = t.number(r, rot);
  }
  return f;
}

std::string vtk_polydata(const Packing& p, const GrainDisplacement* field,
                         const ExportRecord& record) {
  check_field(p, field);
  const LineGeometry g = line_geometry(p);
  std::string out =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" "
      "header_type=\"UInt64\">\n  <PolyData>\n";
  field_data(out, p, field, record);
  out += "    <Piece NumberOfPoints=\"" + std::to_string(g.position.size()) +
         "\" NumberOfVerts=\"0\" NumberOfLines=\"" + std::to_string(p.contacts.size()) +
         "\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n";
  point_data(out, p, g, field);
  cell_data(out, p);
  out += "      <Points>\n";
  data_array(out, "Float64", "", g.position.size(), 3,
             [&](std::size_t i, int c) { return c < 2 ? g.position[i][c] : 0.0; });
  out += "      </Points>\n      <Lines>\n";
  const std::size_t m = p.contacts.size();
  data_array(out, "Int64", "connectivity", 2 * m, 1, [&](std::size_t i, int) {
    return i % 2 == 0 ? p.contacts[i / 2].a : g.end[i / 2];
  });
  data_array(out, "Int64", "offsets", m, 1, [](std::size_t k, int) { return 2.0 * (k + 1); });
  out += "      </Lines>\n    </Piece>\n  </PolyData>\n</VTKFile>\n";
  return out;
}

std::string extended_xyz(const Packing& p, const GrainDisplacement* field,
                         const ExportRecord& record) {
  check_field(p, field);
  const auto& P = p.particles;
  const auto quoted = [](std::string s) {
    std::replace(s.begin(), s.end(), '"', '\'');
    return '"' + s + '"';
  };
  const double R_max = P.size() ? *std::max_element(P.radius.begin(), P.radius.end()) : 1.0;
  std::string out = std::to_string(p.size()) + "\nLattice=\"";
  const double lattice[9] = {p.cell.Lx, 0, 0, 0, p.cell.Ly, 0, 0, 0, 2.0 * R_max};
  for (int i = 0; i < 9; ++i) {
    if (i > 0) out += ' ';
    append_number(out, lattice[i]);
  }
  out += "\" Properties=id:I:1:pos:R:3:radius:R:1:velo:R:3:omega:R:1";
  if (field) out += ":disp:R:3:disp_g:R:3:rot:R:1";
  out += " pbc=\"T T F\" mu=";
  append_number(out, p.meta.contact.mu);
  out += " P_ext=";
  append_number(out, p.meta.contact.P_ext);
  out += " F0=";
  append_number(out, p.force_unit());
  out += " seed=" + std::to_string(p.meta.seed);
  if (field) out += " probed_contact=" + std::to_string(field->contact);
  out += " program_version=" + quoted(kVersion) + " source=" + quoted(record.source) +
         " command=" + quoted(record.command) + '\n';
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double row[] = {P.x[i], P.y[i], 0.0, P.radius[i], P.vx[i], P.vy[i], 0.0, P.omega[i]};
    append_number(out, static_cast<std::int64_t>(i));
    for (const double v : row) append_number(out += ' ', v);
    if (field) {
      const double extra[] = {field->u[i].x(), field->u[i].y(), 0.0, field->u_over_g[i].x(),
                              field->u_over_g[i].y(), 0.0, field->rot[i]};
      for (const double v : extra) append_number(out += ' ', v);
    }
    out += '\n';
  }
  return out;
}

}  // namespace unjam
