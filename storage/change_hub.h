// The listeners of a store's change feed (Store::subscribe): a store publishes each change
// after its commit and every live subscription's listener is called with it. Shared by the
// SQLite store (changes it commits) and the PostgreSQL store (changes heard by LISTEN).
#pragma once

#include <memory>
#include <mutex>
#include <vector>

#include "storage/store.h"

namespace keel::storage {

class ChangeHub {
 public:
  ChangeHub();
  ~ChangeHub();
  ChangeHub(const ChangeHub&) = delete;
  ChangeHub& operator=(const ChangeHub&) = delete;

  // The listener is called for every change published until the subscription is destroyed;
  // destroying it waits for a call in progress on another thread (and may be done from
  // inside the listener itself).
  std::unique_ptr<Subscription> subscribe(ChangeListener listener);
  // Calls every live listener on this thread; a listener that throws is logged and skipped.
  void publish(const std::vector<Change>& changes);
  size_t listeners() const;

 private:
  struct Entry;
  class Handle;
  struct Shared {
    mutable std::mutex mutex;
    std::vector<std::shared_ptr<Entry>> entries;
  };
  std::shared_ptr<Shared> shared_;
};

}  // namespace keel::storage
