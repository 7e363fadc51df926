// A Beast Body that streams bytes [offset, offset + length) of an open file with pread(),
// 64 KiB at a time, so a 1 GiB artifact or a Range of it is never loaded whole. Beast 1.74's
// file_body always starts at the beginning of the file, hence this body.
// Included only by http_server.cc and http_session.cc (Beast is heavy).
#pragma once

#include <boost/asio/buffer.hpp>
#include <boost/beast/http/message.hpp>
#include <boost/optional.hpp>
#include <boost/system/error_code.hpp>

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <filesystem>
#include <utility>

namespace keel::server {

struct FileRegionBody {
  class value_type {
   public:
    value_type() = default;
    ~value_type() { reset(); }
    value_type(value_type&& other) noexcept
        : fd_(std::exchange(other.fd_, -1)), offset_(other.offset_), length_(other.length_) {}
    value_type& operator=(value_type&& other) noexcept {
      if (this != &other) {
        reset();
        fd_ = std::exchange(other.fd_, -1);
        offset_ = other.offset_;
        length_ = other.length_;
      }
      return *this;
    }
    value_type(const value_type&) = delete;
    value_type& operator=(const value_type&) = delete;

    // Opens `path` read-only; the region must lie inside the file.
    void open(const std::filesystem::path& path, uint64_t offset, uint64_t length,
              boost::system::error_code& ec) {
      reset();
      fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
      if (fd_ < 0) {
        ec.assign(errno, boost::system::generic_category());
        return;
      }
      offset_ = offset;
      length_ = length;
      ec = {};
    }
    uint64_t length() const { return length_; }

   private:
    friend struct FileRegionBody;
    void reset() {
      if (fd_ >= 0) ::close(fd_);
      fd_ = -1;
    }
    int fd_ = -1;
    uint64_t offset_ = 0;
    uint64_t length_ = 0;
  };

  static std::uint64_t size(const value_type& body) { return body.length_; }

  class writer {
   public:
    using const_buffers_type = boost::asio::const_buffer;

    template <bool isRequest, class Fields>
    writer(const boost::beast::http::header<isRequest, Fields>&, const value_type& body)
        : body_(body) {}

    void init(boost::system::error_code& ec) {
      position_ = body_.offset_;
      remaining_ = body_.length_;
      ec = {};
    }

    boost::optional<std::pair<const_buffers_type, bool>> get(boost::system::error_code& ec) {
      if (remaining_ == 0) {
        ec = {};
        return boost::none;
      }
      size_t amount =
          remaining_ < sizeof(buffer_) ? static_cast<size_t>(remaining_) : sizeof(buffer_);
      ssize_t got;
      do {
        got = ::pread(body_.fd_, buffer_, amount, static_cast<off_t>(position_));
      } while (got < 0 && errno == EINTR);
      if (got <= 0) {  // an error, or the file is shorter than the region announced
        ec.assign(got < 0 ? errno : EIO, boost::system::generic_category());
        return boost::none;
      }
      position_ += static_cast<uint64_t>(got);
      remaining_ -= static_cast<uint64_t>(got);
      ec = {};
      return {{const_buffers_type(buffer_, static_cast<size_t>(got)), remaining_ > 0}};
    }

   private:
    const value_type& body_;
    uint64_t position_ = 0;
    uint64_t remaining_ = 0;
    char buffer_[64 * 1024];
  };
};

}  // namespace keel::server
