#include "store/h5/run_file.h"

#include <hdf5.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <utility>

#include "common/version.h"

namespace flume::h5 {
namespace {

static_assert(sizeof(hid_t) == sizeof(std::int64_t), "Reader stores an hid_t in an int64_t");

// Silences HDF5's own printing of its error stack while an operation runs: failures are reported once, as
// an exception carrying the innermost HDF5 message, instead of a page of stack on stderr.
class QuietErrors {
 public:
  QuietErrors() {
    H5Eget_auto2(H5E_DEFAULT, &func_, &data_);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  }
  ~QuietErrors() { H5Eset_auto2(H5E_DEFAULT, func_, data_); }
  QuietErrors(const QuietErrors&) = delete;
  QuietErrors& operator=(const QuietErrors&) = delete;

 private:
  H5E_auto2_t func_ = nullptr;
  void* data_ = nullptr;
};

// The deepest message on the HDF5 error stack (it names the cause, e.g. "errno = 28, ... No space left").
std::string hdf5_cause() {
  std::string cause;
  H5Ewalk2(
      H5E_DEFAULT, H5E_WALK_DOWNWARD,
      [](unsigned, const H5E_error2_t* err, void* out) -> herr_t {
        if (err->desc && *err->desc) *static_cast<std::string*>(out) = err->desc;
        return 0;
      },
      &cause);
  return cause;
}

[[noreturn]] void fail(const std::string& file, const std::string& what) {
  std::string cause = hdf5_cause();
  throw std::runtime_error(file + ": " + what + (cause.empty() ? std::string() : " (HDF5: " + cause + ")"));
}

// Owns one HDF5 identifier and closes it with the matching H5?close.
class Id {
 public:
  Id() = default;
  Id(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  ~Id() { reset(); }
  Id(Id&& o) noexcept : id_(std::exchange(o.id_, H5I_INVALID_HID)), close_(o.close_) {}
  Id& operator=(Id&& o) noexcept {
    if (this != &o) {
      reset();
      id_ = std::exchange(o.id_, H5I_INVALID_HID);
      close_ = o.close_;
    }
    return *this;
  }
  Id(const Id&) = delete;
  Id& operator=(const Id&) = delete;
  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }
  // Closes now and reports whether the close (which is where buffered writes may fail) succeeded.
  bool close() {
    if (id_ < 0) return true;
    herr_t rc = close_(id_);
    id_ = H5I_INVALID_HID;
    return rc >= 0;
  }
  void reset() { close(); }

 private:
  hid_t id_ = H5I_INVALID_HID;
  herr_t (*close_)(hid_t) = nullptr;
};

std::vector<std::string> split_path(const std::string& path) {
  std::vector<std::string> parts;
  std::string cur;
  for (char c : path) {
    if (c == '/') {
      if (!cur.empty()) parts.push_back(std::move(cur));
      cur.clear();
    } else {
      cur += c;
    }
  }
  if (!cur.empty()) parts.push_back(std::move(cur));
  return parts;
}

void check_name(const std::string& file, const std::string& name) {
  if (name.empty() || name == "." || name.find('/') != std::string::npos)
    throw std::invalid_argument(file + ": invalid HDF5 member name '" + name + "' (non-empty, no '/')");
}

std::string xml_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string format_double(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

bool deflate_available() {
  if (H5Zfilter_avail(H5Z_FILTER_DEFLATE) <= 0) return false;
  unsigned int info = 0;
  if (H5Zget_filter_info(H5Z_FILTER_DEFLATE, &info) < 0) return false;
  return (info & H5Z_FILTER_CONFIG_ENCODE_ENABLED) != 0;
}

struct SnapshotRecord {
  std::size_t index;
  double time;
  std::size_t n;
  std::vector<std::string> scalars;
  std::vector<std::string> vectors;
};

std::string snapshot_name(std::size_t index) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%05zu", index);
  return buf;
}

}  // namespace

struct RunFile::Impl {
  std::string path;
  std::string part;
  Id file;
  bool finalized = false;
  bool compress = false;
  std::vector<SnapshotRecord> snapshots;
  struct BoxFrame {
    double time;
    std::size_t bodies;
  };
  std::vector<BoxFrame> box_frames;

  void open_file(bool create) {
    QuietErrors quiet;
    Id fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
    // STRONG: closing the file closes anything still open in it, so finalize() really ends with a closed file.
    if (!fapl.valid() || H5Pset_fclose_degree(fapl.get(), H5F_CLOSE_STRONG) < 0) fail(part, "cannot set up file access");
    file = Id(create ? H5Fcreate(part.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get())
                     : H5Fopen(part.c_str(), H5F_ACC_RDWR, fapl.get()),
              H5Fclose);
    if (!file.valid()) fail(part, create ? "cannot create HDF5 file" : "cannot open HDF5 file");
  }

  void require_open() const {
    if (finalized) throw std::logic_error(path + ": written to after finalize()");
    if (!file.valid()) throw std::logic_error(path + ": file is not open");
  }

  // Opens the group at `group_path`, creating the missing parts of it.
  Id group(const std::string& group_path) {
    Id cur(H5Gopen2(file.get(), "/", H5P_DEFAULT), H5Gclose);
    if (!cur.valid()) fail(part, "cannot open the root group");
    std::string so_far;
    for (const std::string& part_name : split_path(group_path)) {
      so_far += "/" + part_name;
      htri_t exists = H5Lexists(cur.get(), part_name.c_str(), H5P_DEFAULT);
      if (exists < 0) fail(part, "cannot look up group " + so_far);
      Id next(exists > 0 ? H5Gopen2(cur.get(), part_name.c_str(), H5P_DEFAULT)
                         : H5Gcreate2(cur.get(), part_name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
              H5Gclose);
      if (!next.valid()) fail(part, (exists > 0 ? "cannot open group " : "cannot create group ") + so_far);
      cur = std::move(next);
    }
    return cur;
  }

  void write_dataset(hid_t parent, const std::string& where, const std::string& name, hid_t file_type,
                     hid_t mem_type, const std::vector<hsize_t>& dims, const void* data, bool chunk) {
    htri_t exists = H5Lexists(parent, name.c_str(), H5P_DEFAULT);
    if (exists < 0) fail(part, "cannot look up " + where);
    if (exists > 0) throw std::invalid_argument(part + ": dataset " + where + " already exists");
    Id space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), H5Sclose);
    if (!space.valid()) fail(part, "cannot create the dataspace of " + where);
    Id dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
    hsize_t rows = dims.empty() ? 0 : dims[0];
    // Chunking (needed by the filters) cannot describe an empty dataset; those stay contiguous.
    if (chunk && compress && rows > 0) {
      std::vector<hsize_t> chunk_dims = dims;
      chunk_dims[0] = std::min<hsize_t>(rows, 65536);
      if (H5Pset_chunk(dcpl.get(), static_cast<int>(dims.size()), chunk_dims.data()) < 0 ||
          H5Pset_shuffle(dcpl.get()) < 0 || H5Pset_deflate(dcpl.get(), 4) < 0)
        fail(part, "cannot set up compression for " + where);
    }
    Id dset(H5Dcreate2(parent, name.c_str(), file_type, space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT),
            H5Dclose);
    if (!dset.valid()) fail(part, "cannot create dataset " + where);
    if (H5Sget_simple_extent_npoints(space.get()) > 0 &&
        H5Dwrite(dset.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0)
      fail(part, "cannot write dataset " + where);
    if (!dset.close()) fail(part, "cannot close dataset " + where);
  }

  // Writes rows [held, rows) of a float64 series of `cols` columns (0: 1-D) into an extendible dataset,
  // creating it (chunked, unlimited rows) the first time.
  void append_dataset(const std::string& group_path, const std::string& name, const double* data,
                      std::size_t rows, std::size_t cols) {
    require_open();
    check_name(path, name);
    const std::string where = group_path + "/" + name;
    QuietErrors quiet;
    Id g = group(group_path);
    const int rank = cols == 0 ? 1 : 2;
    const hsize_t width = cols == 0 ? 1 : cols;
    htri_t exists = H5Lexists(g.get(), name.c_str(), H5P_DEFAULT);
    if (exists < 0) fail(part, "cannot look up " + where);
    Id dset;
    if (exists == 0) {
      const hsize_t dims[2] = {0, width}, max[2] = {H5S_UNLIMITED, width};
      // About 32 KiB a chunk: small enough that a short series wastes little, large enough to append fast.
      const hsize_t chunk[2] = {std::max<hsize_t>(1, 4096 / width), width};
      Id space(H5Screate_simple(rank, dims, max), H5Sclose);
      Id dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
      if (!space.valid() || !dcpl.valid() || H5Pset_chunk(dcpl.get(), rank, chunk) < 0)
        fail(part, "cannot set up the extendible dataset " + where);
      dset = Id(H5Dcreate2(g.get(), name.c_str(), H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, dcpl.get(),
                           H5P_DEFAULT),
                H5Dclose);
      if (!dset.valid()) fail(part, "cannot create dataset " + where);
    } else {
      dset = Id(H5Dopen2(g.get(), name.c_str(), H5P_DEFAULT), H5Dclose);
      if (!dset.valid()) fail(part, "cannot open dataset " + where);
    }
    Id space(H5Dget_space(dset.get()), H5Sclose);
    hsize_t held[2] = {0, 0};
    if (H5Sget_simple_extent_ndims(space.get()) != rank || H5Sget_simple_extent_dims(space.get(), held, nullptr) < 0 ||
        (rank == 2 && held[1] != width))
      throw std::logic_error(part + ": " + where + " changed shape between appends");
    if (rows < held[0])
      throw std::logic_error(part + ": " + where + " shrank from " + std::to_string(held[0]) + " to " +
                             std::to_string(rows) + " rows");
    if (rows == held[0]) return;
    const hsize_t total[2] = {rows, width}, start[2] = {held[0], 0}, count[2] = {rows - held[0], width};
    if (H5Dset_extent(dset.get(), total) < 0) fail(part, "cannot extend " + where);
    Id file_space(H5Dget_space(dset.get()), H5Sclose);
    Id mem_space(H5Screate_simple(rank, count, nullptr), H5Sclose);
    if (H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, start, nullptr, count, nullptr) < 0 ||
        H5Dwrite(dset.get(), H5T_NATIVE_DOUBLE, mem_space.get(), file_space.get(), H5P_DEFAULT,
                 data + held[0] * width) < 0)
      fail(part, "cannot append to " + where);
    if (!dset.close()) fail(part, "cannot close dataset " + where);
  }

  // Replaces attribute `name` on `group_path` with a scalar of `file_type`.
  void write_attribute(const std::string& group_path, const std::string& name, hid_t file_type,
                       hid_t mem_type, const void* value) {
    require_open();
    check_name(path, name);
    QuietErrors quiet;
    Id g = group(group_path);
    std::string where = group_path + "@" + name;
    htri_t exists = H5Aexists(g.get(), name.c_str());
    if (exists < 0) fail(part, "cannot look up attribute " + where);
    if (exists > 0 && H5Adelete(g.get(), name.c_str()) < 0) fail(part, "cannot replace attribute " + where);
    Id space(H5Screate(H5S_SCALAR), H5Sclose);
    Id attr(H5Acreate2(g.get(), name.c_str(), file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
    if (!attr.valid()) fail(part, "cannot create attribute " + where);
    if (H5Awrite(attr.get(), mem_type, value) < 0) fail(part, "cannot write attribute " + where);
  }

  void write_xdmf(const std::string& xmf_path) const {
    std::string h5_name = std::filesystem::path(path).filename().string();
    std::ostringstream x;
    x << "<?xml version=\"1.0\" ?>\n"
      << "<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
      << "<Xdmf Version=\"2.0\">\n <Domain>\n";
    if (!snapshots.empty()) x << "  <Grid Name=\"particles\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
    auto item = [&](const std::string& dataset, std::size_t n, int cols) {
      std::string dims = std::to_string(n) + (cols > 1 ? " " + std::to_string(cols) : std::string());
      x << "     <DataItem Dimensions=\"" << dims << "\" NumberType=\"Float\" Precision=\"4\" Format=\"HDF\">"
        << xml_escape(h5_name + ":" + dataset) << "</DataItem>\n";
    };
    for (const SnapshotRecord& s : snapshots) {
      std::string base = "/snapshots/" + snapshot_name(s.index);
      x << "   <Grid Name=\"" << snapshot_name(s.index) << "\" GridType=\"Uniform\">\n"
        << "    <Time Value=\"" << format_double(s.time) << "\"/>\n"
        << "    <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << s.n
        << "\" NodesPerElement=\"1\"/>\n"
        << "    <Geometry GeometryType=\"XYZ\">\n";
      item(base + "/xyz", s.n, 3);
      x << "    </Geometry>\n";
      for (const std::string& f : s.scalars) {
        x << "    <Attribute Name=\"" << xml_escape(f) << "\" AttributeType=\"Scalar\" Center=\"Node\">\n";
        item(base + "/" + f, s.n, 1);
        x << "    </Attribute>\n";
      }
      for (const std::string& f : s.vectors) {
        x << "    <Attribute Name=\"" << xml_escape(f) << "\" AttributeType=\"Vector\" Center=\"Node\">\n";
        item(base + "/" + f, s.n, 3);
        x << "    </Attribute>\n";
      }
      x << "   </Grid>\n";
    }
    if (!snapshots.empty()) x << "  </Grid>\n";
    // The debris boxes: a temporal collection of their own (ParaView lists both grids).
    if (!box_frames.empty()) {
      x << "  <Grid Name=\"debris\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
      for (std::size_t k = 0; k < box_frames.size(); ++k) {
        const BoxFrame& f = box_frames[k];
        x << "   <Grid Name=\"debris_" << snapshot_name(k) << "\" GridType=\"Uniform\">\n"
          << "    <Time Value=\"" << format_double(f.time) << "\"/>\n"
          << "    <Topology TopologyType=\"Hexahedron\" NumberOfElements=\"" << f.bodies << "\">\n"
          << "     <DataItem Dimensions=\"" << f.bodies << " 8\" NumberType=\"Int\" Format=\"XML\">";
        for (std::size_t i = 0; i < 8 * f.bodies; ++i) x << (i % 8 == 0 ? "\n      " : " ") << i;
        x << "\n     </DataItem>\n    </Topology>\n    <Geometry GeometryType=\"XYZ\">\n";
        x << "     <DataItem Dimensions=\"" << 8 * f.bodies << " 3\" NumberType=\"Float\" Precision=\"4\" "
          << "Format=\"HDF\">" << xml_escape(h5_name + ":/debris_frames/" + snapshot_name(k) + "/corners")
          << "</DataItem>\n    </Geometry>\n"
          << "    <Attribute Name=\"body\" AttributeType=\"Scalar\" Center=\"Cell\">\n"
          << "     <DataItem Dimensions=\"" << f.bodies << "\" NumberType=\"Int\" Format=\"XML\">";
        for (std::size_t b = 0; b < f.bodies; ++b) x << (b ? " " : "") << b;
        x << "</DataItem>\n    </Attribute>\n   </Grid>\n";
      }
      x << "  </Grid>\n";
    }
    x << " </Domain>\n</Xdmf>\n";

    std::string tmp = xmf_path + ".part";
    {
      std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
      if (!out) throw std::runtime_error(tmp + ": cannot create: " + std::strerror(errno));
      out << x.str();
      out.flush();
      if (!out) throw std::runtime_error(tmp + ": cannot write: " + std::strerror(errno));
    }
    std::error_code ec;
    std::filesystem::rename(tmp, xmf_path, ec);
    if (ec) throw std::runtime_error(xmf_path + ": cannot rename from " + tmp + ": " + ec.message());
  }
};

RunFile::RunFile(std::string path) : impl_(std::make_unique<Impl>()) {
  impl_->path = std::move(path);
  impl_->part = impl_->path + ".part";
  impl_->compress = deflate_available();
  // A result left by an earlier run at this path would read as this run's result if this one is killed.
  std::error_code ec;
  std::filesystem::remove(impl_->path, ec);
  std::filesystem::remove(xdmf_path(), ec);
  impl_->open_file(true);
  set_attribute("/", "flume_version", build_info::version());
  set_attribute("/", "flume_git_version", build_info::commit());
}

RunFile::RunFile(std::string path, double keep_snapshots_before) : impl_(std::make_unique<Impl>()) {
  impl_->path = std::move(path);
  impl_->part = impl_->path + ".part";
  impl_->compress = deflate_available();
  std::error_code ec;
  // A finished run extended to a later end time: its result becomes the file in progress again.
  if (!std::filesystem::exists(impl_->part) && std::filesystem::exists(impl_->path))
    std::filesystem::rename(impl_->path, impl_->part, ec);
  std::filesystem::remove(impl_->path, ec);
  std::filesystem::remove(xdmf_path(), ec);
  // What the stopped run wrote: its snapshots (names sort in index order) and, if it was killed while writing
  // its records, parts of those, which the resumed run writes again.
  std::vector<SnapshotRecord> kept;
  std::vector<std::string> drop;
  bool usable = std::filesystem::exists(impl_->part);
  if (usable) {
    try {
      Reader r(impl_->part);
      for (const std::string& name : r.list("/"))
        if (name != "snapshots") drop.push_back("/" + name);
      if (r.exists("/snapshots"))
        for (const std::string& name : r.list("/snapshots")) {
          const std::string base = "/snapshots/" + name;
          const double t = r.number_attribute(base, "time");
          if (!(t < keep_snapshots_before) || name != snapshot_name(kept.size())) {
            drop.push_back(base);
            continue;
          }
          SnapshotRecord rec{kept.size(), t, static_cast<std::size_t>(r.number_attribute(base, "count")), {}, {}};
          for (const std::string& field : r.list(base))
            if (field != "xyz") (r.shape(base + "/" + field).size() == 1 ? rec.scalars : rec.vectors).push_back(field);
          kept.push_back(std::move(rec));
        }
    } catch (const std::exception&) {
      usable = false;  // a file the kill left unreadable: its snapshots are lost, the run goes on
      kept.clear();
      drop.clear();
    }
  }
  impl_->open_file(!usable);
  {
    QuietErrors quiet;
    for (const std::string& link : drop)
      if (H5Ldelete(impl_->file.get(), link.c_str(), H5P_DEFAULT) < 0) fail(impl_->part, "cannot drop " + link);
  }
  impl_->snapshots = std::move(kept);
  set_attribute("/", "flume_version", build_info::version());
  set_attribute("/", "flume_git_version", build_info::commit());
}

RunFile::~RunFile() = default;
RunFile::RunFile(RunFile&&) noexcept = default;
RunFile& RunFile::operator=(RunFile&&) noexcept = default;

const std::string& RunFile::path() const { return impl_->path; }
std::string RunFile::part_path() const { return impl_->part; }
std::string RunFile::xdmf_path() const {
  return std::filesystem::path(impl_->path).replace_extension(".xmf").string();
}
bool RunFile::finalized() const { return impl_->finalized; }
std::size_t RunFile::snapshot_count() const { return impl_->snapshots.size(); }
std::vector<double> RunFile::snapshot_times() const {
  std::vector<double> t;
  for (const auto& s : impl_->snapshots) t.push_back(s.time);
  return t;
}

void RunFile::add_box_frame(double time, std::size_t bodies, const float* corners) {
  impl_->require_open();
  if (bodies > 0 && !corners) throw std::invalid_argument(impl_->path + ": box frame with no corners");
  QuietErrors quiet;
  const std::string base = "/debris_frames/" + snapshot_name(impl_->box_frames.size());
  Id g = impl_->group(base);
  impl_->write_dataset(g.get(), base + "/corners", "corners", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT,
                       {static_cast<hsize_t>(bodies) * 8, 3}, corners, false);
  g.reset();
  set_attribute(base, "time", time);
  impl_->box_frames.push_back({time, bodies});
}

void RunFile::write_series(const std::string& group_path, const std::string& name,
                           const std::vector<double>& values) {
  impl_->require_open();
  check_name(impl_->path, name);
  QuietErrors quiet;
  Id g = impl_->group(group_path);
  impl_->write_dataset(g.get(), group_path + "/" + name, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE,
                       {static_cast<hsize_t>(values.size())}, values.data(), false);
}

void RunFile::write_matrix(const std::string& group_path, const std::string& name,
                           const std::vector<double>& row_major, std::size_t cols) {
  impl_->require_open();
  check_name(impl_->path, name);
  std::string where = group_path + "/" + name;
  if (cols == 0 || row_major.size() % cols != 0)
    throw std::invalid_argument(impl_->path + ": " + where + ": " + std::to_string(row_major.size()) +
                                " values do not fill rows of " + std::to_string(cols) + " columns");
  QuietErrors quiet;
  Id g = impl_->group(group_path);
  impl_->write_dataset(g.get(), where, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE,
                       {static_cast<hsize_t>(row_major.size() / cols), static_cast<hsize_t>(cols)},
                       row_major.data(), false);
}

void RunFile::append_series(const std::string& group_path, const std::string& name,
                            const std::vector<double>& values) {
  impl_->append_dataset(group_path, name, values.data(), values.size(), 0);
}

void RunFile::append_matrix(const std::string& group_path, const std::string& name,
                            const std::vector<double>& row_major, std::size_t cols) {
  if (cols == 0 || row_major.size() % cols != 0)
    throw std::invalid_argument(impl_->path + ": " + group_path + "/" + name + ": " +
                                std::to_string(row_major.size()) + " values do not fill rows of " +
                                std::to_string(cols) + " columns");
  impl_->append_dataset(group_path, name, row_major.data(), row_major.size() / cols, cols);
}

void RunFile::set_attribute(const std::string& group_path, const std::string& name,
                            const std::string& value) {
  // Fixed-length, null-padded UTF-8: the string form h5py, h5dump and ParaView's readers all take.
  Id type(H5Tcopy(H5T_C_S1), H5Tclose);
  if (!type.valid() || H5Tset_size(type.get(), std::max<std::size_t>(value.size(), 1)) < 0 ||
      H5Tset_strpad(type.get(), H5T_STR_NULLPAD) < 0 || H5Tset_cset(type.get(), H5T_CSET_UTF8) < 0)
    fail(impl_->part, "cannot make a string type for attribute " + name);
  std::string padded = value.empty() ? std::string(1, '\0') : value;
  impl_->write_attribute(group_path, name, type.get(), type.get(), padded.data());
}

void RunFile::set_attribute(const std::string& group_path, const std::string& name, const char* value) {
  set_attribute(group_path, name, std::string(value ? value : ""));
}

void RunFile::set_attribute(const std::string& group_path, const std::string& name, double value) {
  impl_->write_attribute(group_path, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &value);
}

void RunFile::set_attribute(const std::string& group_path, const std::string& name, std::int64_t value) {
  impl_->write_attribute(group_path, name, H5T_STD_I64LE, H5T_NATIVE_INT64, &value);
}

std::size_t RunFile::add_snapshot(double time, std::size_t n, const float* xyz,
                                  const std::vector<Field>& scalars, const std::vector<Field>& vectors) {
  impl_->require_open();
  const std::string& file = impl_->path;
  if (n > 0 && !xyz)
    throw std::invalid_argument(file + ": snapshot with " + std::to_string(n) + " particles and no xyz");
  std::vector<std::string> seen{"xyz"};
  for (const auto* list : {&scalars, &vectors}) {
    for (const Field& f : *list) {
      check_name(file, f.name);
      for (const std::string& s : seen)
        if (s == f.name)
          throw std::invalid_argument(file + ": snapshot field '" + f.name + "' given twice or reserved");
      seen.push_back(f.name);
      if (n > 0 && !f.data)
        throw std::invalid_argument(file + ": snapshot field '" + f.name + "' has no data");
    }
  }

  QuietErrors quiet;
  SnapshotRecord rec{impl_->snapshots.size(), time, n, {}, {}};
  std::string base = "/snapshots/" + snapshot_name(rec.index);
  Id g = impl_->group(base);
  auto write = [&](const std::string& name, const float* data, hsize_t cols) {
    std::vector<hsize_t> dims{static_cast<hsize_t>(n)};
    if (cols > 1) dims.push_back(cols);
    impl_->write_dataset(g.get(), base + "/" + name, name, H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, dims, data,
                         true);
  };
  write("xyz", xyz, 3);
  for (const Field& f : scalars) {
    write(f.name, f.data, 1);
    rec.scalars.push_back(f.name);
  }
  for (const Field& f : vectors) {
    write(f.name, f.data, 3);
    rec.vectors.push_back(f.name);
  }
  g.reset();
  set_attribute(base, "time", time);
  set_attribute(base, "count", static_cast<std::int64_t>(n));
  impl_->snapshots.push_back(std::move(rec));
  return impl_->snapshots.back().index;
}

void RunFile::flush() {
  impl_->require_open();
  QuietErrors quiet;
  if (H5Fflush(impl_->file.get(), H5F_SCOPE_GLOBAL) < 0) fail(impl_->part, "cannot flush");
}

void RunFile::finalize() {
  impl_->require_open();
  {
    QuietErrors quiet;
    set_attribute("/", "snapshot_count", static_cast<std::int64_t>(impl_->snapshots.size()));
    // Buffered data reaches the disk here; a full disk shows up as a failed flush or close.
    if (H5Fflush(impl_->file.get(), H5F_SCOPE_GLOBAL) < 0) fail(impl_->part, "cannot flush");
    if (!impl_->file.close()) fail(impl_->part, "cannot close");
  }
  std::string xmf = xdmf_path();
  if (!impl_->snapshots.empty() || !impl_->box_frames.empty()) {
    impl_->write_xdmf(xmf);
  }
  // The HDF5 file is renamed last: its final name existing is the signal that the run's output is complete.
  std::error_code ec;
  std::filesystem::rename(impl_->part, impl_->path, ec);
  if (ec) throw std::runtime_error(impl_->path + ": cannot rename from " + impl_->part + ": " + ec.message());
  impl_->finalized = true;
}

// ---------------------------------------------------------------------------------------------- Reader

Reader::Reader(const std::string& file) : file_(file) {
  QuietErrors quiet;
  id_ = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (id_ < 0) fail(file, "cannot open HDF5 file");
}

Reader::~Reader() {
  if (id_ >= 0) H5Fclose(id_);
}

bool Reader::exists(const std::string& object_path) const {
  QuietErrors quiet;
  std::string so_far;
  for (const std::string& part : split_path(object_path)) {
    so_far += "/" + part;
    htri_t e = H5Lexists(id_, so_far.c_str(), H5P_DEFAULT);
    if (e < 0) fail(file_, "cannot look up " + so_far);
    if (e == 0) return false;
  }
  return true;
}

std::vector<double> Reader::read_vector(const std::string& dataset_path) const {
  QuietErrors quiet;
  Id dset(H5Dopen2(id_, dataset_path.c_str(), H5P_DEFAULT), H5Dclose);
  if (!dset.valid()) fail(file_, "cannot open dataset " + dataset_path);
  Id type(H5Dget_type(dset.get()), H5Tclose);
  H5T_class_t cls = H5Tget_class(type.get());
  if (cls != H5T_FLOAT && cls != H5T_INTEGER)
    throw std::runtime_error(file_ + ": " + dataset_path + " is not numeric");
  Id space(H5Dget_space(dset.get()), H5Sclose);
  hssize_t count = H5Sget_simple_extent_npoints(space.get());
  if (count < 0) fail(file_, "cannot read the shape of " + dataset_path);
  std::vector<double> out(static_cast<std::size_t>(count));
  if (count > 0 && H5Dread(dset.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) < 0)
    fail(file_, "cannot read dataset " + dataset_path);
  return out;
}

std::vector<std::size_t> Reader::shape(const std::string& dataset_path) const {
  QuietErrors quiet;
  Id dset(H5Dopen2(id_, dataset_path.c_str(), H5P_DEFAULT), H5Dclose);
  if (!dset.valid()) fail(file_, "cannot open dataset " + dataset_path);
  Id space(H5Dget_space(dset.get()), H5Sclose);
  int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank < 0) fail(file_, "cannot read the shape of " + dataset_path);
  std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
  H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  return std::vector<std::size_t>(dims.begin(), dims.end());
}

std::vector<std::string> Reader::list(const std::string& group_path) const {
  QuietErrors quiet;
  Id g(H5Gopen2(id_, group_path.c_str(), H5P_DEFAULT), H5Gclose);
  if (!g.valid()) fail(file_, "cannot open group " + group_path);
  std::vector<std::string> names;
  hsize_t idx = 0;
  herr_t rc = H5Literate(
      g.get(), H5_INDEX_NAME, H5_ITER_INC, &idx,
      [](hid_t, const char* name, const H5L_info_t*, void* out) -> herr_t {
        static_cast<std::vector<std::string>*>(out)->push_back(name);
        return 0;
      },
      &names);
  if (rc < 0) fail(file_, "cannot list group " + group_path);
  return names;
}

std::string Reader::string_attribute(const std::string& object_path, const std::string& name) const {
  QuietErrors quiet;
  std::string where = object_path + "@" + name;
  Id attr(H5Aopen_by_name(id_, object_path.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  if (!attr.valid()) fail(file_, "cannot open attribute " + where);
  Id type(H5Aget_type(attr.get()), H5Tclose);
  if (H5Tget_class(type.get()) != H5T_STRING)
    throw std::runtime_error(file_ + ": " + where + " is not a string");
  if (H5Tis_variable_str(type.get()) > 0) {
    Id mem(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(mem.get(), H5T_VARIABLE);
    char* s = nullptr;
    if (H5Aread(attr.get(), mem.get(), &s) < 0) fail(file_, "cannot read attribute " + where);
    std::string out = s ? s : "";
    H5free_memory(s);
    return out;
  }
  std::string buf(H5Tget_size(type.get()), '\0');
  if (H5Aread(attr.get(), type.get(), buf.data()) < 0) fail(file_, "cannot read attribute " + where);
  return buf.substr(0, buf.find('\0'));
}

double Reader::number_attribute(const std::string& object_path, const std::string& name) const {
  QuietErrors quiet;
  std::string where = object_path + "@" + name;
  Id attr(H5Aopen_by_name(id_, object_path.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  if (!attr.valid()) fail(file_, "cannot open attribute " + where);
  Id type(H5Aget_type(attr.get()), H5Tclose);
  H5T_class_t cls = H5Tget_class(type.get());
  if (cls != H5T_FLOAT && cls != H5T_INTEGER)
    throw std::runtime_error(file_ + ": " + where + " is not a number");
  Id space(H5Aget_space(attr.get()), H5Sclose);
  if (H5Sget_simple_extent_npoints(space.get()) != 1)
    throw std::runtime_error(file_ + ": " + where + " is not a single number");
  double v = 0;
  if (H5Aread(attr.get(), H5T_NATIVE_DOUBLE, &v) < 0) fail(file_, "cannot read attribute " + where);
  return v;
}

std::vector<double> read_vector(const std::string& file, const std::string& dataset_path) {
  return Reader(file).read_vector(dataset_path);
}

}  // namespace flume::h5
