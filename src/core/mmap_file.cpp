#include "core/mmap_file.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <utility>

#include "core/error.h"

namespace mebake {

namespace {
constexpr uint64_t kGrowQuantum = uint64_t(64) << 20;  // remap in 64 MiB steps

uint64_t RoundCapacity(uint64_t size) {
    return size == 0 ? 0 : (size + kGrowQuantum - 1) / kGrowQuantum * kGrowQuantum;
}
}  // namespace

MappedFile::~MappedFile() { Close(); }

MappedFile::MappedFile(MappedFile&& o) noexcept { *this = std::move(o); }

MappedFile& MappedFile::operator=(MappedFile&& o) noexcept {
    if (this != &o) {
        Close();
        path_ = std::move(o.path_);
        fd_ = std::exchange(o.fd_, -1);
        data_ = std::exchange(o.data_, nullptr);
        size_ = std::exchange(o.size_, 0);
        mapped_ = std::exchange(o.mapped_, 0);
        mode_ = o.mode_;
    }
    return *this;
}

MappedFile MappedFile::Open(const std::string& path, Mode mode) {
    MappedFile f;
    f.path_ = path;
    f.mode_ = mode;
    f.fd_ = ::open(path.c_str(), (mode == Mode::ReadOnly ? O_RDONLY : O_RDWR) | O_CLOEXEC);
    if (f.fd_ < 0) IoError({path}, "cannot open: {}", ErrnoString(errno));
    struct stat st {};
    if (::fstat(f.fd_, &st) != 0) IoError({path}, "cannot stat: {}", ErrnoString(errno));
    f.size_ = uint64_t(st.st_size);
    f.mapped_ = f.size_;
    if (f.size_ > 0) {
        int prot = mode == Mode::ReadOnly ? PROT_READ : PROT_READ | PROT_WRITE;
        f.data_ = ::mmap(nullptr, f.size_, prot, MAP_SHARED, f.fd_, 0);
        if (f.data_ == MAP_FAILED) {
            f.data_ = nullptr;
            IoError({path}, "cannot map {} bytes: {}", f.size_, ErrnoString(errno));
        }
    }
    return f;
}

MappedFile MappedFile::Create(const std::string& path, uint64_t size) {
    MappedFile f;
    f.path_ = path;
    f.mode_ = Mode::ReadWrite;
    f.fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (f.fd_ < 0) IoError({path}, "cannot create: {}", ErrnoString(errno));
    f.Resize(size);
    return f;
}

void MappedFile::Resize(uint64_t size) {
    if (mode_ != Mode::ReadWrite) IoError({path_}, "resize of a read-only mapping");
    uint64_t cap = RoundCapacity(size);
    if (cap != mapped_) {
        // Reserve the file's blocks so a full disk fails here, with a message, rather
        // than as SIGBUS on a later write into the mapping.
        if (cap > mapped_) {
            int rc = ::posix_fallocate(fd_, off_t(mapped_), off_t(cap - mapped_));
            if (rc != 0) IoError({path_}, "cannot grow to {} bytes: {}", cap, ErrnoString(rc));
        } else if (::ftruncate(fd_, off_t(cap)) != 0) {
            IoError({path_}, "cannot shrink to {} bytes: {}", cap, ErrnoString(errno));
        }
        void* p = nullptr;
        if (data_ == nullptr) {
            p = cap ? ::mmap(nullptr, cap, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, 0) : nullptr;
        } else if (cap == 0) {
            ::munmap(data_, mapped_);
        } else {
            p = ::mremap(data_, mapped_, cap, MREMAP_MAYMOVE);
        }
        if (p == MAP_FAILED) {
            data_ = nullptr;
            mapped_ = 0;
            IoError({path_}, "cannot map {} bytes: {}", cap, ErrnoString(errno));
        }
        data_ = p;
        mapped_ = cap;
    }
    size_ = size;
}

void MappedFile::Sync(bool durable) {
    if (data_ && mode_ == Mode::ReadWrite && ::msync(data_, mapped_, MS_SYNC) != 0)
        IoError({path_}, "cannot write back: {}", ErrnoString(errno));
    if (durable && fd_ >= 0 && ::fsync(fd_) != 0)
        IoError({path_}, "fsync failed: {}", ErrnoString(errno));
}

void MappedFile::DontNeed(uint64_t offset, uint64_t len) {
    if (!data_) return;
    const uint64_t page = uint64_t(::sysconf(_SC_PAGESIZE));
    uint64_t begin = (offset + page - 1) / page * page;
    uint64_t end = std::min(offset + len, mapped_) / page * page;
    if (end > begin) ::madvise(data() + begin, end - begin, MADV_DONTNEED);
}

void MappedFile::Close() {
    if (data_) ::munmap(data_, mapped_);
    data_ = nullptr;
    if (fd_ >= 0) {
        // Trim the page-rounded capacity back to the logical size.
        if (mode_ == Mode::ReadWrite && mapped_ != size_) (void)::ftruncate(fd_, off_t(size_));
        ::close(fd_);
    }
    fd_ = -1;
    size_ = mapped_ = 0;
}

}  // namespace mebake
