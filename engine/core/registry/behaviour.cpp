#include "arbiter/behaviour.hpp"

namespace arbiter {

ValueBox::ValueBox(const ValueType& type)
    : type_(&type),
      storage_(new std::max_align_t[(type.size + sizeof(std::max_align_t) - 1) /
                                        sizeof(std::max_align_t) +
                                    1]) {
  type.construct(storage_.get());
}

ValueBox::ValueBox(ValueBox&& other) noexcept
    : type_(other.type_), storage_(std::move(other.storage_)) {
  other.type_ = nullptr;
}

ValueBox& ValueBox::operator=(ValueBox&& other) noexcept {
  if (this != &other) {
    if (type_ != nullptr && storage_) type_->destroy(storage_.get());
    type_ = other.type_;
    storage_ = std::move(other.storage_);
    other.type_ = nullptr;
  }
  return *this;
}

ValueBox::~ValueBox() {
  if (type_ != nullptr && storage_) type_->destroy(storage_.get());
}

}  // namespace arbiter
