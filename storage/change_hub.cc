#include "storage/change_hub.h"

#include <spdlog/spdlog.h>

#include <algorithm>

namespace keel::storage {

struct ChangeHub::Entry {
  ChangeListener listener;
  // Held while the listener runs; recursive so the listener may end its own subscription.
  std::recursive_mutex calling;
  bool active = true;
};

class ChangeHub::Handle : public Subscription {
 public:
  Handle(std::weak_ptr<Shared> shared, std::shared_ptr<Entry> entry)
      : shared_(std::move(shared)), entry_(std::move(entry)) {}
  ~Handle() override {
    if (auto shared = shared_.lock()) {
      std::lock_guard<std::mutex> lock(shared->mutex);
      auto& entries = shared->entries;
      entries.erase(std::remove(entries.begin(), entries.end(), entry_), entries.end());
    }
    std::lock_guard<std::recursive_mutex> calling(entry_->calling);
    entry_->active = false;
  }

 private:
  std::weak_ptr<Shared> shared_;
  std::shared_ptr<Entry> entry_;
};

ChangeHub::ChangeHub() : shared_(std::make_shared<Shared>()) {}
ChangeHub::~ChangeHub() = default;

std::unique_ptr<Subscription> ChangeHub::subscribe(ChangeListener listener) {
  auto entry = std::make_shared<Entry>();
  entry->listener = std::move(listener);
  {
    std::lock_guard<std::mutex> lock(shared_->mutex);
    shared_->entries.push_back(entry);
  }
  return std::make_unique<Handle>(shared_, entry);
}

void ChangeHub::publish(const std::vector<Change>& changes) {
  if (changes.empty()) return;
  std::vector<std::shared_ptr<Entry>> entries;
  {
    std::lock_guard<std::mutex> lock(shared_->mutex);
    entries = shared_->entries;
  }
  for (const auto& entry : entries) {
    std::lock_guard<std::recursive_mutex> calling(entry->calling);
    for (const Change& change : changes) {
      if (!entry->active) break;
      try {
        entry->listener(change);
      } catch (const std::exception& e) {
        spdlog::error("change listener failed: {}", e.what());
      } catch (...) {
        spdlog::error("change listener failed with a non-standard exception");
      }
    }
  }
}

size_t ChangeHub::listeners() const {
  std::lock_guard<std::mutex> lock(shared_->mutex);
  return shared_->entries.size();
}

}  // namespace keel::storage
