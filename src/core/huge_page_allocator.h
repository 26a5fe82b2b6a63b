#pragma once
/// \file huge_page_allocator.h
/// A std::allocator replacement for the large read-mostly arrays of acceleration structures. Large
/// blocks are 2 MiB aligned and marked MADV_HUGEPAGE, so transparent huge pages back them where the
/// kernel allows it ("madvise" mode is Debian's default). Incoherent rays touch nodes and leaves all
/// over tens of MB: with 4 KiB pages nearly every node visit is also a TLB miss (Embree allocates
/// its nodes the same way for the same reason).
#include <cstddef>
#include <cstdlib>
#include <new>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace tessera {

template <class T>
struct HugePageAllocator {
    using value_type = T;
    static constexpr size_t kHugePage = size_t(2) << 20;

    HugePageAllocator() = default;
    template <class U>
    HugePageAllocator(const HugePageAllocator<U>&) noexcept {}

    T* allocate(size_t n) {
        size_t bytes = n * sizeof(T);
        void* p = nullptr;
        if (bytes >= kHugePage) {
            size_t rounded = (bytes + kHugePage - 1) / kHugePage * kHugePage;
            p = std::aligned_alloc(kHugePage, rounded);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
            if (p) madvise(p, rounded, MADV_HUGEPAGE);  // a hint: failure only costs speed
#endif
        } else {
            size_t align = alignof(T) > alignof(std::max_align_t) ? alignof(T) : alignof(std::max_align_t);
            p = std::aligned_alloc(align, (bytes + align - 1) / align * align);
        }
        if (!p) throw std::bad_alloc();
        return static_cast<T*>(p);
    }
    void deallocate(T* p, size_t) noexcept { std::free(p); }

    template <class U>
    bool operator==(const HugePageAllocator<U>&) const noexcept { return true; }
};

}  // namespace tessera
