// One way to open a store for keel-server and its command-line tools: SQLite in the data
// folder (the default) or PostgreSQL with a shared blob folder, chosen by the database URL.
#pragma once

#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>

#include "storage/store.h"

namespace keel::storage {

struct StoreLocation {
  // "" or "sqlite": SQLite in data_dir (keel.db, blobs/, uploads/).
  // "postgresql://user@host:port/db?...": PostgreSQL; blobs and upload parts in blob_dir.
  std::string database_url;
  std::filesystem::path data_dir;  // this server's own files (SQLite: the whole store)
  std::filesystem::path blob_dir;  // PostgreSQL: the shared blob folder ("" = data_dir)
  bool listen = true;              // PostgreSQL: hear other replicas' changes
};

// Why a store could not be opened, so keel-server can exit with a distinct code.
struct OpenError : std::runtime_error {
  enum class Kind {
    kBadUrl,            // not a database URL Keel knows
    kUnreachable,       // PostgreSQL cannot be reached or refused the connection
    kSchemaTooNew,      // the database was made by a newer Keel
    kBlobDirUnwritable  // the (blob) folder cannot be written
  };
  OpenError(Kind which, const std::string& message) : std::runtime_error(message), kind(which) {}
  Kind kind;
};

// Opens (creating or migrating if needed) the store `location` names. Throws OpenError; a
// failed open leaves nothing running.
std::unique_ptr<Store> open_store(const StoreLocation& location, Clock clock = system_clock_ms);

// "postgresql://user:secret@host/db" -> "postgresql://user:***@host/db", for messages.
std::string redact_database_url(const std::string& url);
// True for postgresql:// and postgres:// URLs.
bool is_postgresql_url(const std::string& url);
// The URL with connect_timeout (seconds) added unless it names one, so an unreachable host
// is an error after a bounded time rather than a hang.
std::string with_connect_timeout(const std::string& url, int seconds);

// Creates `dir` if needed and proves it writable (a file created, fsynced and removed);
// OpenError kBlobDirUnwritable naming the folder otherwise.
void require_writable_folder(const std::filesystem::path& dir, const std::string& what);

}  // namespace keel::storage
