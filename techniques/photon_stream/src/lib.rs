//! Photon streaming with virtual surface lights (Meneveaux & Bridault 2008).
