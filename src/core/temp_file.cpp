#include "core/temp_file.h"

#include "core/error.h"

#include <cerrno>
#include <cstdlib>
#include <fcntl.h>
#include <unistd.h>
#include <vector>

namespace mebake {

std::string TemporaryDirectory(const std::string& dir) {
    if (!dir.empty())
        return dir;
    const char* env = std::getenv("TMPDIR");
    return env && *env ? env : "/tmp";
}

int OpenTemporaryFile(const std::string& dir_in, const std::string& what) {
    const std::string dir = TemporaryDirectory(dir_in);
    int fd = ::open(dir.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
    if (fd >= 0)
        return fd;
    // Filesystems without O_TMPFILE: a named file, unlinked at once.
    const std::string tmpl = dir + "/mebake-" + what + "-XXXXXX";
    std::vector<char> name(tmpl.begin(), tmpl.end());
    name.push_back('\0');
    fd = ::mkostemp(name.data(), O_CLOEXEC);
    if (fd < 0)
        IoError({dir}, "cannot create a temporary file for {}: {}", what, ErrnoString(errno));
    ::unlink(name.data());
    return fd;
}

}  // namespace mebake
