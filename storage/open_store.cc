#include "storage/open_store.h"

#include <regex>

#include "core/durable_file.h"
#include "storage/ids.h"
#include "storage/migrations.h"
#include "storage/pg_connection.h"
#include "storage/pg_store.h"

namespace keel::storage {

namespace fs = std::filesystem;

std::string redact_database_url(const std::string& url) {
  // scheme://user:password@ -> scheme://user:***@
  static const std::regex password(R"(^([a-z]+://[^:/@]*):[^@/]*@)");
  std::string out = std::regex_replace(url, password, "$1:***@");
  static const std::regex query_password(R"(([?&]password=)[^&]*)");
  return std::regex_replace(out, query_password, "$1***");
}

bool is_postgresql_url(const std::string& url) {
  return url.rfind("postgresql://", 0) == 0 || url.rfind("postgres://", 0) == 0;
}

std::string with_connect_timeout(const std::string& url, int seconds) {
  if (url.find("connect_timeout=") != std::string::npos) return url;
  return url + (url.find('?') == std::string::npos ? "?" : "&") +
         "connect_timeout=" + std::to_string(seconds);
}

void require_writable_folder(const fs::path& dir, const std::string& what) {
  const fs::path probe = dir / (".keel-write-test-" + random_hex(8));
  try {
    fs::create_directories(dir);
    {
      DurableFile file(probe, DurableFile::Mode::kCreateNew);
      file.write_at(0, "keel", 4);
      file.sync();
    }
    fs::remove(probe);
  } catch (const std::exception& error) {
    std::error_code ignored;
    fs::remove(probe, ignored);
    throw OpenError(OpenError::Kind::kBlobDirUnwritable,
                    what + " " + dir.string() + " is not writable: " + error.what());
  }
}

std::unique_ptr<Store> open_store(const StoreLocation& location, Clock clock) {
  const std::string& url = location.database_url;
  try {
    if (url.empty() || url == "sqlite") {
      require_writable_folder(location.data_dir, "data folder");
      if (!location.blob_dir.empty() && location.blob_dir != location.data_dir)
        throw OpenError(OpenError::Kind::kBadUrl,
                        "a separate blob folder needs --database postgresql://...; SQLite keeps "
                        "its blobs in the data folder " +
                            location.data_dir.string());
      return open_sqlite_store(location.data_dir, std::move(clock));
    }
    if (!is_postgresql_url(url))
      throw OpenError(OpenError::Kind::kBadUrl,
                      "database '" + redact_database_url(url) +
                          "': expected 'sqlite' or a URL postgresql://user@host:port/database");
    PgStoreOptions options;
    options.database_url = url;
    options.blob_dir = location.blob_dir.empty() ? location.data_dir : location.blob_dir;
    options.listen = location.listen;
    // This server's own files (its first token, server.url) stay in the data folder.
    if (!location.data_dir.empty()) require_writable_folder(location.data_dir, "data folder");
    for (const char* part : {"blobs", "tmp", "uploads"})
      require_writable_folder(options.blob_dir / part, "blob folder");
    return std::make_unique<PgStore>(options, std::move(clock));
  } catch (const SchemaTooNew& error) {
    throw OpenError(OpenError::Kind::kSchemaTooNew, error.what());
  } catch (const Unavailable& error) {
    throw OpenError(OpenError::Kind::kUnreachable, error.what());
  } catch (const pqxx::broken_connection& error) {
    throw OpenError(OpenError::Kind::kUnreachable,
                    "cannot connect to " + redact_database_url(url) + ": " + error.what());
  } catch (const pqxx::sql_error& error) {
    throw OpenError(OpenError::Kind::kUnreachable,
                    "database " + redact_database_url(url) + ": " + error.what());
  }
}

}  // namespace keel::storage
